// `dvso eval-odometry`: KITTI t_rel / r_rel, ATE and RPE of an estimated
// trajectory against ground truth (core/eval_odometry.h; docs/evaluation.md).
#include <filesystem>
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/eval_odometry.h"
#include "core/trajectory.h"
#include "pipelines/commands.h"

namespace dvso::cli {

namespace {

namespace fs = std::filesystem;

struct EvalOdometryArgs {
  std::string gt_path, est_path, gt_times_path, est_times_path, plot_dir;
  std::string align = "none";
  bool json = false;
  OdometryEvalOptions options;
};

Trajectory LoadTrajectory(const std::string& path, const std::string& times_path) {
  if (times_path.empty()) return ReadTrajectory(path, TrajectoryFormat::kAuto);
  const std::vector<double> times = ReadTimes(times_path);
  return ReadTrajectory(path, TrajectoryFormat::kAuto, &times);
}

void Run(EvalOdometryArgs& args) {
  args.options.align = ParseAlignmentMode(args.align);
  args.options.Check();
  // Before any metric is printed: a run must not end in an error after its output.
  if (!args.plot_dir.empty()) {
    RequireFile(!fs::exists(args.plot_dir) || fs::is_directory(args.plot_dir), args.plot_dir,
                "--plot-dir exists and is not a folder");
  }
  const Trajectory gt = LoadTrajectory(args.gt_path, args.gt_times_path);
  const Trajectory est = LoadTrajectory(args.est_path, args.est_times_path);
  if (!args.json) {
    std::cout << "ground truth : " << args.gt_path << (args.gt_times_path.empty() ? "" : " (times " + args.gt_times_path + ")")
              << "\nestimate     : " << args.est_path
              << (args.est_times_path.empty() ? "" : " (times " + args.est_times_path + ")")
              << "\nalign        : " << AlignmentModeName(args.options.align)
              << ", step " << args.options.step_size << " frames, max time difference "
              << args.options.max_time_difference << " s\n\n";
  }
  const OdometryMetrics metrics = EvaluateOdometry(gt, est, args.options);
  if (args.json) {
    std::cout << OdometryMetricsToJson(metrics).dump(2) << std::endl;
  } else {
    std::cout << FormatOdometryMetrics(metrics);
  }
  if (!args.plot_dir.empty()) {
    const std::vector<std::string> written =
        WriteOdometryPlots(args.plot_dir, gt, AlignedMatchedEstimate(gt, est, args.options, metrics), metrics);
    std::ostream& note = args.json ? std::cerr : std::cout;
    for (const std::string& path : written) note << "plot written: " << path << "\n";
    if (metrics.segments == 0) note << "no segment-error plot: " << NoKittiSegmentsReason(metrics) << "\n";
  }
}

}  // namespace

void AddEvalOdometryCommand(CLI::App& app) {
  auto args = std::make_shared<EvalOdometryArgs>();
  auto* cmd = app.add_subcommand(
      "eval-odometry", "KITTI odometry metrics (t_rel %, r_rel deg/100m), ATE after SE3/Sim3 alignment, RPE");
  cmd->add_option("--gt", args->gt_path, "ground-truth trajectory (KITTI 3x4 or TUM; detected)")
      ->required();
  cmd->add_option("--est", args->est_path, "estimated trajectory (KITTI 3x4 or TUM; detected)")
      ->required();
  cmd->add_option("--align", args->align,
                  "align the estimate before ALL metrics: none (KITTI devkit), se3, sim3 (monocular)")
      ->capture_default_str();
  cmd->add_option("--gt-times", args->gt_times_path, "times.txt for a KITTI-format GT (else frame index)");
  cmd->add_option("--est-times", args->est_times_path, "times.txt for a KITTI-format estimate (else frame index)");
  cmd->add_option("--max-time-diff", args->options.max_time_difference,
                  "largest timestamp difference (s) for pairing GT and estimated poses")
      ->capture_default_str();
  cmd->add_option("--rpe-delta", args->options.rpe_delta_frames, "RPE frame distance (GT frames)")
      ->capture_default_str();
  cmd->add_option("--step", args->options.step_size, "KITTI segment start every N-th GT frame (devkit: 10)")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "print exactly one JSON object on stdout");
  cmd->add_option("--plot-dir", args->plot_dir,
                  "write trajectory_xz.png and segment_errors.png into this directory");
  cmd->callback([args] { Run(*args); });
}

}  // namespace dvso::cli
