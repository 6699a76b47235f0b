// `dvso labels`: sparse disparity labels from Stereo DSO (issue 4).
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "core/config_yaml.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "pipelines/commands.h"
#include "sdso_labels/label_runner.h"

namespace dvso::cli {

namespace {

struct LabelsArgs {
  std::string sequence, list, out, config, gt_disparity, gt_subdir, gt_disparity_right, gt_subdir_right,
      preset = "default", cameras = "grey";
  bool preset_given = false;  // --preset on the command line
  int first = 0, count = -1;
  bool json = false, overwrite = false, quiet = false, worker_thread = false, right_labels = false;
};

void RunLabels(const LabelsArgs& args) {
  Require(args.sequence.empty() != args.list.empty(), "give exactly one of --sequence DIR or --list FILE");
  Require((args.gt_disparity.empty() && args.gt_disparity_right.empty()) || args.list.empty(),
          "--gt-disparity(-right) is for one sequence; with --list use --gt-subdir(-right) NAME (e.g. disp_0)");
  labels::LabelRunOptions options;
  if (!args.config.empty()) {
    // --preset is the base the config's odometry keys change (as in `dvso odometry`), unless the
    // config names its own preset: then a different --preset contradicts it.
    if (args.preset_given) {
      YamlSection config = YamlSection::FromFile(args.config);
      std::string config_preset = args.preset;
      config.Read("preset", &config_preset);
      RequireFile(config_preset == args.preset, args.config,
                  "names preset '" + config_preset + "' but --preset " + args.preset + " was given");
    }
    options = labels::LoadLabelRunOptions(args.config, args.preset);
  } else {
    options.odometry = vo::OdometryOptions::Preset(args.preset);
  }
  options.cameras = ParseCameraPair(args.cameras);
  options.first = args.first;
  options.count = args.count;
  options.labels.overwrite = args.overwrite;
  if (args.right_labels) options.labels.right_labels = true;
  options.progress = !args.quiet;
  options.worker_thread = args.worker_thread;
  options.Check();
  // Right GT without right labels would be read by nothing: say so instead of ignoring it.
  Require(options.labels.right_labels || (args.gt_disparity_right.empty() && args.gt_subdir_right.empty()),
          "--gt-disparity-right / --gt-subdir-right need --right-labels (or labels.right_labels: true in --config)");
  if (!args.json) {
    std::cout << "# dvso labels configuration" << (args.config.empty() ? " (preset " + args.preset + ")" : " (" + args.config + ")")
              << "\n" << labels::LabelRunOptionsToYaml(options) << std::endl;
  }
  const std::vector<std::string> sequences =
      args.list.empty() ? std::vector<std::string>{args.sequence} : labels::ReadSequenceList(args.list);
  // With --list, each sequence writes into OUT/<its folder name> ("a/seq/" is "seq" too).
  auto folder_name = [](const std::string& sequence) { return NormalizedFolderPath(sequence).filename().string(); };
  if (!args.list.empty()) {
    // Two sequences with the same folder name would share (and skip) one output folder.
    std::map<std::string, std::string> owner;
    for (const std::string& sequence : sequences) {
      const std::string name = folder_name(sequence);
      const auto [it, fresh] = owner.emplace(name, sequence);
      RequireFile(fresh, args.list, "'" + it->second + "' and '" + sequence + "' would both write " +
                                        JoinPath(args.out, name) + " (sequence folders need distinct names)");
    }
  }
  nlohmann::json all = nlohmann::json::array();
  labels::LabelStatistics total, total_right;
  for (size_t s = 0; s < sequences.size(); ++s) {
    const std::string& sequence = sequences[s];
    const std::string out = args.list.empty()
                                ? args.out
                                : JoinPath(args.out, folder_name(sequence));
    labels::LabelRunOptions run = options;
    run.gt_disparity_dir = !args.gt_disparity.empty() ? args.gt_disparity
                           : !args.gt_subdir.empty()  ? JoinPath(sequence, args.gt_subdir)
                                                      : "";
    run.gt_disparity_right_dir = !args.gt_disparity_right.empty() ? args.gt_disparity_right
                                 : !args.gt_subdir_right.empty()  ? JoinPath(sequence, args.gt_subdir_right)
                                                                  : "";
    if (!args.quiet && sequences.size() > 1) {
      std::cerr << "[" << s + 1 << "/" << sequences.size() << "] " << sequence << std::endl;
    }
    const labels::LabelRunSummary summary = labels::RunLabelExtraction(sequence, out, run);
    all.push_back(summary.ToJson());
    total.Merge(summary.statistics);
    total_right.Merge(summary.right_statistics);
    if (!args.json) {
      std::cout << "== " << sequence << " -> " << out << (summary.skipped_complete ? " (complete, skipped)" : "") << "\n"
                << summary.statistics.ToText();
      if (summary.right_labels) std::cout << "right image:\n" << summary.right_statistics.ToText();
      if (!summary.skipped_complete) {
        std::cout << "stereo check:           kept " << summary.verified_labels << " of " << summary.projected_labels
                  << " projected labels\n"
                  << "odometry:               " << summary.keyframes << " keyframes, " << summary.lost << " lost frames\n"
                  << "speed (ms/frame):       odometry " << summary.odometry_ms_per_frame << ", labels "
                  << summary.labels_ms_per_frame << ", total " << summary.total_ms_per_frame
                  << " (image decoding " << summary.image_read_ms_per_frame << " with " << summary.image_rereads
                  << " pairs read twice, not included; labels on "
                  << (summary.worker_thread ? "a worker thread" : "the odometry thread") << ")\n";
        if (summary.kept_existing_frames > 0) {
          std::cout << "resumed:                kept " << summary.kept_existing_frames
                    << " existing left label files (--overwrite rewrites them): the statistics above are of the files "
                       "on disk, the stereo-check counts of the maps this run computed\n";
        }
      }
      std::cout << std::flush;
    }
  }
  // --sequence: its summary; --list (any length, so scripts get one shape): every summary and the
  // statistics of all sequences' frames together.
  if (args.list.empty()) {
    if (args.json) std::cout << all[0].dump(2) << std::endl;
    return;
  }
  if (args.json) {
    nlohmann::json overall = total.ToJson();
    if (options.labels.right_labels) overall["right"] = total_right.ToJson();
    std::cout << nlohmann::json{{"sequences", all}, {"overall", overall}}.dump(2) << std::endl;
  } else {
    std::cout << "== overall: " << sequences.size() << " sequences\n" << total.ToText();
    if (options.labels.right_labels) std::cout << "right image:\n" << total_right.ToText();
    std::cout << std::flush;
  }
}

}  // namespace

void AddLabelsCommand(CLI::App& app) {
  auto args = std::make_shared<LabelsArgs>();
  auto* cmd = app.add_subcommand("labels", "Sparse disparity labels (KITTI uint16 PNG) from Stereo DSO");
  cmd->add_option("--sequence", args->sequence, "Stereo sequence directory (KITTI layout or EuRoC)");
  cmd->add_option("--list", args->list, "Batch: file listing one sequence directory per line");
  cmd->add_option("--out", args->out, "Output directory (batch: one subfolder per sequence)")->required();
  cmd->add_option("--config", args->config, "YAML with 'labels:', 'odometry:' and 'preset:' keys");
  cmd->add_option("--preset", args->preset,
                  "Odometry preset: default|fast (with --config: the base its odometry keys change, unless it names "
                  "its own preset)");
  cmd->add_option("--gt-disparity", args->gt_disparity, "GT disparity folder (%06d.png) for accuracy statistics");
  cmd->add_option("--gt-subdir", args->gt_subdir, "Batch: GT disparity subfolder inside each sequence (e.g. disp_0)");
  cmd->add_flag("--right-labels", args->right_labels, "Also label the right image (OUT/right/%06d.png)");
  cmd->add_option("--gt-disparity-right", args->gt_disparity_right, "GT disparity folder of the right image (e.g. disp_1)");
  cmd->add_option("--gt-subdir-right", args->gt_subdir_right, "Batch: right GT disparity subfolder (e.g. disp_1)");
  cmd->add_option("--cameras", args->cameras, "KITTI layouts (raw drive, odometry folder): the stereo pair to label, grey (00/01) or colour (02/03)")
      ->capture_default_str();
  cmd->add_option("--first", args->first, "First frame index");
  cmd->add_option("--count", args->count, "Number of frames (-1 = all)");
  cmd->add_flag("--overwrite", args->overwrite, "Rewrite existing label files (default: resume)");
  cmd->add_flag("--json", args->json, "Print the summary as JSON");
  cmd->add_flag("--quiet", args->quiet, "No progress bars");
  cmd->add_flag("--worker-thread", args->worker_thread,
                "Produce labels on a worker thread beside the odometry (helps only with a spare core)");
  cmd->callback([args, cmd] {
    args->preset_given = cmd->count("--preset") > 0;
    RunLabels(*args);
  });
}

}  // namespace dvso::cli
