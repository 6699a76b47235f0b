// `dvso odometry`: direct sparse odometry (mono / stereo / dvso) over a sequence.
// Thin: parses options, loads and prints the config, calls
// vo::RunOdometryOnSequence (vo/system/sequence_runner.h).
#include <cstdlib>
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/sequence.h"
#include "pipelines/commands.h"
#include "pipelines/prediction_source.h"
#include "vo/system/odometry_options.h"
#include "vo/system/sequence_runner.h"

namespace dvso::cli {

namespace {

struct OdometryArgs {
  std::string sequence, mode = "stereo", config, preset = "default", out, camera_file, cameras = "grey";
  int first = 0;
  int count = -1;
  bool ply = false;
  bool no_progress = false;
  bool strict = false;
  bool inference_threads_given = false;  // --inference-threads on the command line
  PredictionSourceArgs predictions;
};

void Run(const OdometryArgs& args) {
  const vo::OdometryMode mode = vo::ParseOdometryMode(args.mode);
  vo::OdometryOptions options = vo::OdometryOptions::Preset(args.preset);
  if (!args.config.empty()) options = vo::LoadOdometryOptions(args.config, options);
  options.Check();
  Require(vo::CapabilitiesOf(mode).has_predictions ||
              (args.predictions.model.empty() && args.predictions.disparity_left.empty() &&
               args.predictions.disparity_right.empty()),
          "--model / --disparity-left/right need --mode dvso");
  const std::unique_ptr<SequenceReader> sequence =
      OpenSequence(args.sequence, args.camera_file, ParseCameraPair(args.cameras));
  const StereoCamera& cam = sequence->camera();
  PredictionSource predictions;
  if (vo::CapabilitiesOf(mode).has_predictions) {
    predictions = OpenPredictionSource(args.predictions, *sequence);
    ApplyPredictionSource(args.predictions, &predictions, &options);
  } else {
    // Not an error: scripts pass one set of extra options to every mode (benchmarks/run_dvso.sh).
    if (args.predictions.virtual_baseline > 0 || !args.predictions.schedule.empty() || args.inference_threads_given) {
      std::cerr << "dvso: note: --virtual-baseline / --prediction-schedule / --inference-threads only act in --mode "
                   "dvso; ignored\n";
    }
  }
  std::cout << "dvso odometry: " << args.sequence << " (" << sequence->size() << " frames, " << cam.left.width << "x"
            << cam.left.height << ", fx " << cam.left.fx << ", baseline " << cam.baseline << " m)\n"
            << "mode: " << vo::ToString(mode) << ", preset: " << args.preset
            << (args.config.empty() ? "" : ", config: " + args.config) << "\n"
            << (predictions.source ? "predictions: " + predictions.description + ", " +
                                         options.dvso.prediction_timing + "\n"
                                   : std::string())
            << "--- config ---\n"
            << vo::OdometryOptionsToYaml(options) << "--------------\n";
  vo::SequenceRunOptions run;
  run.first = args.first;
  run.count = args.count;
  run.write_ply = args.ply;
  run.progress = !args.no_progress;
  run.predictions = predictions.source.get();
  run.strict = args.strict;
  run.stop_on_interrupt = true;
  const vo::SequenceRunSummary s = vo::RunOdometryOnSequence(*sequence, options, mode, args.out, run);
  std::cout << "frames " << s.frames << ", keyframes " << s.keyframes << ", lost " << s.lost << " (unreadable "
            << s.unreadable << "), initializing " << s.initializing << ", re-initialisations " << s.resets << "\n"
            << "mean " << s.mean_ms << " ms/frame (max " << s.max_ms << " ms), wall " << s.wall_ms
            << " ms/frame incl. reading\n";
  // Modes that start metric make their first frame a keyframe at the origin: that one is no estimate.
  const int estimates = vo::CapabilitiesOf(mode).StartsMetric() ? s.tracked - 1 : s.tracked;
  if (s.frames > 0 && estimates <= 0) {
    // Every line of the trajectory is an initialiser's guess, a lost frame or the origin: say so where a
    // script looks.
    std::cerr << "dvso: warning: no frame was tracked (" << s.initializing << " initializing, " << s.lost
              << " lost of " << s.frames << "): the trajectory holds no estimate; check the images and the "
              << "calibration (mono also needs the camera to translate, or use --mode stereo / dvso)\n";
  }
  if (predictions.worker != nullptr) {
    std::cout << "predictions (" << options.dvso.prediction_timing << "): " << predictions.worker->prefetched_used()
              << " requested ahead, " << predictions.worker->computed_on_demand() << " computed on demand\n";
  }
  if (args.ply) std::cout << "points.ply: " << s.ply_points << " points\n";
  if (s.interrupted) {
    std::cout << "interrupted: outputs hold the " << s.frames << " frames processed (marker " << args.out
              << "/INTERRUPTED)" << std::endl;
    // Join the prediction worker before leaving: std::exit skips the destructors
    // of this frame's locals, and a worker thread still running at exit aborts.
    predictions = PredictionSource{};
    std::exit(130);  // the conventional exit status after SIGINT
  }
  std::cout << "written: " << args.out << "/trajectory.txt, trajectory_tum.txt, run_log.csv, config.yaml"
            << (args.ply ? ", points.ply" : "") << "\n";
}

}  // namespace

void AddOdometryCommand(CLI::App& app) {
  auto args = std::make_shared<OdometryArgs>();
  auto* cmd = app.add_subcommand("odometry", "Direct sparse odometry (mono, stereo or dvso) over a sequence");
  cmd->add_option("--sequence", args->sequence, "Sequence directory (KITTI layout, EuRoC, or image folder)")
      ->required();
  cmd->add_option("--mode", args->mode,
                  "mono (DSO) | stereo (Stereo DSO) | dvso (monocular + predicted disparities, metric)")
      ->check(CLI::IsMember({"mono", "stereo", "dvso"}));
  AddPredictionOptions(cmd, &args->predictions, vo::OdometryOptions().dvso.prediction_timing);
  cmd->add_option("--config", args->config, "YAML options (strict keys; applied on top of the preset)");
  cmd->add_option("--preset", args->preset, "default (2000 points) | fast (800 points)")
      ->check(CLI::IsMember({"default", "fast"}));
  cmd->add_option("--out", args->out, "Output directory")->required();
  cmd->add_option("--first", args->first,
                  "First frame index (trajectory.txt then starts at this frame, with no frame numbers: compare it with "
                  "the GT from line --first on, e.g. `tail -n +$((first+1)) poses.txt`; trajectory_tum.txt carries the "
                  "sequence's times and evaluates as it is)");
  cmd->add_option("--count", args->count, "Number of frames (-1 = all)");
  cmd->add_option("--camera", args->camera_file, "DSO camera file (image-folder sequences only)");
  cmd->add_option("--cameras", args->cameras, "KITTI layouts (raw drive, odometry folder): grey (00/01) or colour (02/03, read as grey) pair")
      ->capture_default_str();
  cmd->add_flag("--ply", args->ply, "Also write points.ply (marginalised points)");
  cmd->add_flag("--no-progress", args->no_progress, "No progress bar");
  cmd->add_flag("--strict", args->strict,
                "Stop at the first unreadable image (default: warn, count it as a lost frame, go on)");
  cmd->callback([args, cmd] {
    args->inference_threads_given = cmd->count("--inference-threads") > 0;
    Run(*args);
  });
}

}  // namespace dvso::cli
