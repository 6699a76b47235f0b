// `dvso calibrate-vignette`: the left lens's vignetting from a recording (vo/system/vignette_calibration.h).
// Thin: parses options, runs the calibration, writes and summarises its files.
#include <algorithm>
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "pipelines/commands.h"
#include "vo/system/odometry_options.h"
#include "vo/system/vignette_calibration.h"

namespace dvso::cli {

namespace {

struct CalibrateVignetteArgs {
  std::string sequence, mode = "auto", config, out, camera_file, cameras = "grey";
  int first = 0;
  int count = 500;  // the fit is dense in the keyframes: a few hundred frames suffice and stay quick
  bool no_progress = false;
  bool count_given = false;
  vo::VignetteCalibrationOptions calibration;
};

void Run(const CalibrateVignetteArgs& args) {
  const std::unique_ptr<SequenceReader> sequence =
      OpenSequence(args.sequence, args.camera_file, ParseCameraPair(args.cameras));
  const vo::OdometryMode mode = args.mode == "auto" ? (sequence->is_stereo() ? vo::OdometryMode::kStereo
                                                                             : vo::OdometryMode::kMono)
                                                    : vo::ParseOdometryMode(args.mode);
  vo::OdometryOptions options;
  if (!args.config.empty()) options = vo::LoadOdometryOptions(args.config, options);
  options.Check();
  std::cout << "dvso calibrate-vignette: " << args.sequence << " (" << sequence->size() << " frames), "
            << vo::ToString(mode) << " odometry" << (args.config.empty() ? "" : ", config " + args.config) << "\n";
  vo::SequenceRunOptions run;
  run.first = args.first;
  // The default 500 frames, or the rest of a shorter sequence (no past-the-end warning for the default).
  const bool first_inside = args.first >= 0 && args.first < sequence->size();
  run.count = args.count_given || args.count < 0 || !first_inside ? args.count
                                                                  : std::min(args.count, sequence->size() - args.first);
  run.progress = !args.no_progress;
  const vo::VignetteCalibration c = vo::CalibrateVignette(*sequence, options, mode, args.out, run, args.calibration);
  vo::WriteVignetteCalibration(args.out, c);
  std::cout << "keyframes " << c.keyframes << " (segments " << c.segments << "), points " << c.fit.points
            << ", samples " << c.fit.observations << "\ncoefficients:";
  for (double v : c.fit.vignette.coefficients) std::cout << " " << v;
  std::cout << "  (V = 1 + c1 rho^2 + c2 rho^4 ...; V at the half diagonal " << c.fit.vignette.At(1.0)
            << ")\nrms residual " << c.fit.rms << " grey levels (" << c.fit.rms_without_vignette
            << " without a vignette)\nwritten: " << args.out
            << "/vignette.png (use as `vignette_file:` in an odometry config), vignette_fit.yaml, "
               "vignette_profile.png, and the odometry run's trajectory.txt, run_log.csv, config.yaml\n";
}

}  // namespace

void AddCalibrateVignetteCommand(CLI::App& app) {
  auto args = std::make_shared<CalibrateVignetteArgs>();
  auto* cmd = app.add_subcommand(
      "calibrate-vignette",
      "Estimate the left lens's vignetting from a sequence (no target needed); writes a vignette_file");
  cmd->add_option("--sequence", args->sequence, "Sequence directory (KITTI layout, EuRoC, or image folder)")
      ->required();
  cmd->add_option("--out", args->out, "Output directory")->required();
  cmd->add_option("--mode", args->mode, "odometry that finds the points: auto (stereo when there is a right image) | "
                                        "mono | stereo")
      ->check(CLI::IsMember({"auto", "mono", "stereo"}))
      ->capture_default_str();
  cmd->add_option("--config", args->config, "Odometry YAML options (strict keys; no vignette_file)");
  cmd->add_option("--first", args->first, "First frame index");
  cmd->add_option("--count", args->count,
                  "Number of frames (-1 = all; the fit's system is dense in the keyframes, so thousands take long)")
      ->capture_default_str();
  cmd->add_option("--camera", args->camera_file, "DSO camera file (image-folder sequences only)");
  cmd->add_option("--cameras", args->cameras, "KITTI layouts: grey (00/01) or colour (02/03, read as grey) pair")
      ->capture_default_str();
  cmd->add_option("--coefficients", args->calibration.fit.num_coefficients,
                  "Polynomial terms of V in rho^2 (0-4)")
      ->check(CLI::Range(0, 4))
      ->capture_default_str();
  cmd->add_option("--neighbour-keyframes", args->calibration.neighbour_keyframes,
                  "A point is sampled in this many keyframes before and after its host")
      ->check(Positive())
      ->capture_default_str();
  cmd->add_option("--blur-fraction", args->calibration.blur_fraction,
                  "Gaussian blur before sampling, sigma as a fraction of the image width")
      ->check(CLI::Range(0.0, 0.1))
      ->capture_default_str();
  cmd->add_option("--max-sample-gradient", args->calibration.max_sample_gradient,
                  "Samples where the blurred image is steeper (grey levels / px) are dropped; 0 = keep all")
      ->check(NonNegative())
      ->capture_default_str();
  cmd->add_flag("--no-progress", args->no_progress, "No progress bars");
  cmd->callback([args, cmd] {
    args->count_given = cmd->count("--count") > 0;
    Run(*args);
  });
}

}  // namespace dvso::cli
