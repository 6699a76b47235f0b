// `dvso demo`: the whole toolkit on data the repo generates itself — a
// synthetic street along a real KITTI trajectory, stereo and monocular
// odometry, their KITTI-protocol evaluation with plots, and Stereo-DSO labels
// checked against the exact ground truth, and DVSO (monocular + the network's
// disparities) without alignment. With LibTorch and a committed
// model, the depth network is run on it too (pipelines/torch_demo.cpp).
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/eval_odometry.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "core/simulator.h"
#include "core/trajectory.h"
#include "pipelines/commands.h"
#include "pipelines/demo_steps.h"
#include "pipelines/prediction_source.h"
#include "sdso_labels/label_runner.h"
#include "vo/system/odometry_options.h"
#include "vo/system/sequence_runner.h"

namespace dvso::cli {

namespace {

struct DemoArgs {
  std::string out = "demo_out";
  std::string data_dir = DVSO_SOURCE_DIR "/data";
  std::string model = std::string(DVSO_SOURCE_DIR) + "/" + kShippedModel;
  std::string kitti_sequence = "07";
  int first = 0;
  int frames = 150;
  int width = 0, height = 0;  // 0 = KITTI 1241x376
  bool quiet = false;
};

nlohmann::json EvaluateRun(const std::string& gt_path, const std::string& run_dir, AlignmentMode align,
                           const std::string& label) {
  OdometryEvalOptions options;
  options.align = align;
  const Trajectory gt = ReadTrajectory(gt_path);
  const Trajectory est = ReadTrajectory(JoinPath(run_dir, "trajectory.txt"));
  const OdometryMetrics metrics = EvaluateOdometry(gt, est, options);
  WriteOdometryPlots(run_dir, gt, AlignedMatchedEstimate(gt, est, options, metrics), metrics);
  std::cout << "\n== " << label << " ==\n" << FormatOdometryMetrics(metrics);
  return OdometryMetricsToJson(metrics);
}

void RunDemo(const DemoArgs& args) {
  const std::string poses = JoinPath(JoinPath(args.data_dir, "kitti_poses"), args.kitti_sequence + ".txt");
  RequireFile(std::filesystem::is_regular_file(poses), poses, "KITTI pose file not found (see --data-dir)");
  EnsureDirectory(args.out);
  const std::string sequence_dir = JoinPath(args.out, "sequence");
  nlohmann::json summary;

  // 1. A synthetic street along the real KITTI trajectory, with exact GT.
  SimulatorOptions sim;
  sim.trajectory_path = poses;
  sim.first_frame = args.first;
  sim.num_frames = args.frames;
  Require((args.width > 0) == (args.height > 0), "give both --width and --height (or neither: KITTI 1241x376)");
  if (args.width > 0) sim.camera = sim.camera.Resized(args.width, args.height);
  std::cout << "== 1/4 simulate: " << args.frames << " frames along KITTI " << args.kitti_sequence << " ("
            << sim.camera.left.width << "x" << sim.camera.left.height << ") -> " << sequence_dir << std::endl;
  const SimulationSummary simulated = WriteSimulatedSequence(sim, sequence_dir, !args.quiet);
  summary["simulation"] = {{"frames", simulated.frames},
                           {"seconds", simulated.seconds},
                           {"path_length_m", simulated.path_length}};
  const auto sequence = OpenSequence(sequence_dir);
  const std::string gt = JoinPath(sequence_dir, "poses.txt");

  // 2. Stereo and monocular odometry, evaluated with the KITTI protocol.
  const vo::OdometryOptions odometry = vo::OdometryOptions::Preset("default");
  vo::SequenceRunOptions run;
  run.progress = !args.quiet;
  std::cout << "\n== 2/4 odometry (stereo, mono, dvso)" << std::endl;
  const auto stereo = vo::RunOdometryOnSequence(*sequence, odometry, vo::OdometryMode::kStereo,
                                                JoinPath(args.out, "odometry_stereo"), run);
  const auto mono = vo::RunOdometryOnSequence(*sequence, odometry, vo::OdometryMode::kMono,
                                              JoinPath(args.out, "odometry_mono"), run);
  summary["odometry_stereo"] = EvaluateRun(gt, JoinPath(args.out, "odometry_stereo"), AlignmentMode::kNone,
                                           "stereo odometry (no alignment)");
  summary["odometry_stereo"]["ms_per_frame"] = stereo.mean_ms;
  summary["odometry_stereo"]["lost_frames"] = stereo.lost;
  summary["odometry_mono"] = EvaluateRun(gt, JoinPath(args.out, "odometry_mono"), AlignmentMode::kSim3,
                                         "monocular odometry (Sim3-aligned: scale is not observable)");
  summary["odometry_mono"]["ms_per_frame"] = mono.mean_ms;
  summary["odometry_mono"]["lost_frames"] = mono.lost;

  // DVSO: the left images only, metric from the network's disparities (or,
  // without LibTorch / model, from the simulator's exact ones).
  PredictionSourceArgs prediction_args;
  std::string dvso_label = "dvso odometry with the model (monocular, no alignment)";
#ifdef DVSO_WITH_TORCH
  const bool have_model = std::filesystem::is_regular_file(args.model);
#else
  const bool have_model = false;
#endif
  if (have_model) {
    prediction_args.model = args.model;
  } else {
    prediction_args.disparity_left = JoinPath(sequence_dir, "disp_0");
    prediction_args.disparity_right = JoinPath(sequence_dir, "disp_1");
    dvso_label = "dvso odometry with the exact disparities (no model in this build; no alignment)";
  }
  PredictionSource predictions = OpenPredictionSource(prediction_args, *sequence);
  vo::OdometryOptions dvso_options = odometry;
  ApplyPredictionSource(prediction_args, &predictions, &dvso_options);
  vo::SequenceRunOptions dvso_run = run;
  dvso_run.predictions = predictions.source.get();
  const auto dvso = vo::RunOdometryOnSequence(*sequence, dvso_options, vo::OdometryMode::kDvso,
                                              JoinPath(args.out, "odometry_dvso"), dvso_run);
  summary["odometry_dvso"] = EvaluateRun(gt, JoinPath(args.out, "odometry_dvso"), AlignmentMode::kNone, dvso_label);
  summary["odometry_dvso"]["ms_per_frame"] = dvso.mean_ms;
  summary["odometry_dvso"]["lost_frames"] = dvso.lost;
  summary["odometry_dvso"]["predictions"] = predictions.description;

  // 3. Stereo DSO sparse disparity labels, against the exact GT disparity.
  std::cout << "\n== 3/4 labels (Stereo DSO sparse disparity)" << std::endl;
  labels::LabelRunOptions label_options;
  label_options.progress = !args.quiet;
  label_options.labels.overwrite = true;
  label_options.gt_disparity_dir = JoinPath(sequence_dir, "disp_0");
  const auto labelled = labels::RunLabelExtraction(sequence_dir, JoinPath(args.out, "labels"), label_options);
  std::cout << labelled.statistics.ToText();
  summary["labels"] = labelled.ToJson();

  // 4. The depth network (only with LibTorch and a model).
  std::cout << "\n== 4/4 depth network" << std::endl;
  summary["depth_network"] = RunDemoDepthNetwork(args.model, sequence_dir, JoinPath(args.out, "prediction"), !args.quiet);

  const std::string json_path = JoinPath(args.out, "demo_summary.json");
  std::ofstream(json_path) << summary.dump(2) << "\n";
  std::cout << "\nsummary: " << json_path << "\nplots:   " << args.out << "/odometry_*/trajectory_xz.png" << std::endl;
}

}  // namespace

void AddDemoCommand(CLI::App& app) {
  auto args = std::make_shared<DemoArgs>();
  auto* cmd = app.add_subcommand("demo", "Simulate a street sequence, run stereo/mono/dvso odometry, labels, evaluate");
  cmd->add_option("--out", args->out, "Output directory")->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames to simulate")->capture_default_str()->check(CLI::Range(20, 100000));
  cmd->add_option("--first", args->first, "First KITTI pose")->capture_default_str();
  cmd->add_option("--kitti-sequence", args->kitti_sequence, "Which real KITTI trajectory to follow (00..10)")
      ->capture_default_str();
  cmd->add_option("--width", args->width, "Image width (default KITTI 1241)");
  cmd->add_option("--height", args->height, "Image height (default KITTI 376)");
  cmd->add_option("--data-dir", args->data_dir, "The repository's data/ folder")->capture_default_str();
  cmd->add_option("--model", args->model,
                  "TorchScript model for the depth-network step (a named file must exist; without the shipped one the "
                  "step is skipped)")
      ->capture_default_str()
      ->check(CLI::ExistingFile);
  cmd->add_flag("--quiet", args->quiet, "No progress bars");
  cmd->callback([args] { RunDemo(*args); });
}

}  // namespace dvso::cli
