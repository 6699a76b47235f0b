#include "sdso_labels/label_runner.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "core/config_yaml.h"
#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "sdso_labels/pair_cache.h"
#include "vo/system/sequence_runner.h"

namespace dvso::labels {

namespace fs = std::filesystem;

void LabelRunOptions::Check() const {
  labels.Check();
  odometry.Check();
  Require(first >= 0, "labels: first must be >= 0");
  Require(count == -1 || count >= 1, "labels: count must be >= 1 (or -1 for all)");
  Require(image_cache_pairs >= 1, "labels: image_cache_pairs must be >= 1");
}

LabelRunOptions LoadLabelRunOptions(const std::string& path, const std::string& preset_without_key) {
  YamlSection root = YamlSection::FromFile(path);
  LabelRunOptions options;
  std::string preset = preset_without_key;
  root.Read("preset", &preset);
  options.odometry = vo::OdometryOptions::Preset(preset);
  YamlSection& labels = root.Child("labels");
  labels.Read("min_good_residuals", &options.labels.min_good_residuals);
  labels.Read("max_depth", &options.labels.max_depth);
  labels.Read("max_disparity_stddev", &options.labels.max_disparity_stddev);
  labels.Read("max_mean_energy", &options.labels.max_mean_energy);
  labels.Read("max_stereo_energy", &options.labels.max_stereo_energy);
  labels.Read("max_stereo_energy_ratio", &options.labels.max_stereo_energy_ratio);
  labels.Read("stereo_energy_ratio_floor", &options.labels.stereo_energy_ratio_floor);
  labels.Read("future_keyframes", &options.labels.future_keyframes);
  labels.Read("past_keyframes", &options.labels.past_keyframes);
  labels.Read("right_labels", &options.labels.right_labels);
  labels.Read("keyframe_candidates", &options.labels.keyframe_candidates);
  YamlSection& check = labels.Child("stereo_check");
  check.Read("enabled", &options.labels.stereo_check.enabled);
  check.Read("window_radius", &options.labels.stereo_check.window_radius);
  check.Read("max_offset", &options.labels.stereo_check.max_offset);
  check.Read("exclusion", &options.labels.stereo_check.exclusion);
  check.Read("min_cost_gap", &options.labels.stereo_check.min_cost_gap);
  check.Read("max_cost", &options.labels.stereo_check.max_cost);
  check.Read("max_disparity", &options.labels.stereo_check.max_disparity);
  check.Read("left_right_check", &options.labels.stereo_check.left_right_check);
  check.Read("edge_shift", &options.labels.stereo_check.edge_shift);
  check.Read("edge_max_cost", &options.labels.stereo_check.edge_max_cost);
  check.Read("edge_distinct_gap", &options.labels.stereo_check.edge_distinct_gap);
  labels.Read("occlusion_radius", &options.labels.projection.occlusion_radius);
  labels.Read("occlusion_margin", &options.labels.projection.occlusion_margin);
  labels.Read("min_depth", &options.labels.projection.min_depth);
  labels.Read("max_disparity", &options.labels.projection.max_disparity);
  labels.Read("edge_radius", &options.labels.projection.edge_radius);
  labels.Read("edge_margin", &options.labels.projection.edge_margin);
  root.MarkUsed("odometry");  // validated strictly by the odometry's own loader below
  root.RequireAllKeysUsed();
  if (root.Has("odometry")) {
    std::stringstream text;
    text << root.node()["odometry"];
    try {
      options.odometry = vo::OdometryOptionsFromYamlString(text.str(), options.odometry);
    } catch (const Error& e) {
      throw Error(path, std::string("odometry section: ") + e.what());
    }
  }
  options.Check();
  return options;
}

std::string LabelRunOptionsToYaml(const LabelRunOptions& options) {
  std::ostringstream out;
  const auto& l = options.labels;
  out << "labels:\n"
      << "  min_good_residuals: " << l.min_good_residuals << "\n"
      << "  max_depth: " << l.max_depth << "\n"
      << "  max_disparity_stddev: " << l.max_disparity_stddev << "\n"
      << "  max_mean_energy: " << l.max_mean_energy << "\n"
      << "  max_stereo_energy: " << l.max_stereo_energy << "\n"
      << "  max_stereo_energy_ratio: " << l.max_stereo_energy_ratio << "\n"
      << "  stereo_energy_ratio_floor: " << l.stereo_energy_ratio_floor << "\n"
      << "  future_keyframes: " << l.future_keyframes << "\n"
      << "  past_keyframes: " << l.past_keyframes << "\n"
      << "  right_labels: " << (l.right_labels ? "true" : "false") << "\n"
      << "  keyframe_candidates: " << (l.keyframe_candidates ? "true" : "false") << "\n"
      << "  stereo_check:\n"
      << "    enabled: " << (l.stereo_check.enabled ? "true" : "false") << "\n"
      << "    window_radius: " << l.stereo_check.window_radius << "\n"
      << "    max_offset: " << l.stereo_check.max_offset << "\n"
      << "    exclusion: " << l.stereo_check.exclusion << "\n"
      << "    min_cost_gap: " << l.stereo_check.min_cost_gap << "\n"
      << "    max_cost: " << l.stereo_check.max_cost << "\n"
      << "    max_disparity: " << l.stereo_check.max_disparity << "\n"
      << "    left_right_check: " << (l.stereo_check.left_right_check ? "true" : "false") << "\n"
      << "    edge_shift: " << l.stereo_check.edge_shift << "\n"
      << "    edge_max_cost: " << l.stereo_check.edge_max_cost << "\n"
      << "    edge_distinct_gap: " << l.stereo_check.edge_distinct_gap << "\n"
      << "  occlusion_radius: " << l.projection.occlusion_radius << "\n"
      << "  occlusion_margin: " << l.projection.occlusion_margin << "\n"
      << "  min_depth: " << l.projection.min_depth << "\n"
      << "  max_disparity: " << l.projection.max_disparity << "\n"
      << "  edge_radius: " << l.projection.edge_radius << "\n"
      << "  edge_margin: " << l.projection.edge_margin << "\n"
      << "odometry:\n";
  std::istringstream odometry(vo::OdometryOptionsToYaml(options.odometry));
  for (std::string line; std::getline(odometry, line);) out << "  " << line << "\n";
  return out.str();
}

nlohmann::json LabelRunSummary::ToJson() const {
  nlohmann::json j = statistics.ToJson();
  j["sequence"] = sequence;
  j["cameras"] = cameras;
  j["skipped_complete"] = skipped_complete;
  if (right_labels) {
    j["right"] = right_statistics.ToJson();
    if (!skipped_complete) {
      j["right"]["projected_labels"] = right_projected_labels;
      j["right"]["verified_labels"] = right_verified_labels;
    }
  }
  if (!skipped_complete) {
    j["kept_existing_frames"] = kept_existing_frames;
    j["odometry_ms_per_frame"] = odometry_ms_per_frame;
    j["labels_ms_per_frame"] = labels_ms_per_frame;
    j["labels_on_worker_thread"] = worker_thread;
    j["total_ms_per_frame"] = total_ms_per_frame;
    j["image_read_ms_per_frame"] = image_read_ms_per_frame;
    j["image_rereads"] = image_rereads;
    j["projected_labels"] = projected_labels;
    j["verified_labels"] = verified_labels;
    j["keyframes"] = keyframes;
    j["lost_frames"] = lost;
  }
  return j;
}

namespace {

// The ground-truth map of a frame, which must be a map of the sequence's images (GT of another
// resolution is an error naming the file, not a size mismatch deep in the statistics).
cv::Mat GroundTruth(const std::string& dir, int frame_index, int width, int height) {
  if (dir.empty()) return cv::Mat();
  const std::string path = JoinPath(dir, FrameFileName(frame_index, ".png"));
  cv::Mat gt = ReadKittiMapPng(path);
  RequireFile(gt.cols == width && gt.rows == height, path,
              "ground-truth disparity is " + std::to_string(gt.cols) + "x" + std::to_string(gt.rows) +
                  ", the sequence's images are " + std::to_string(width) + "x" + std::to_string(height));
  return gt;
}

// Labels already in the folder were made on the pair its summary names: a resume that reads another pair
// would keep them and record the new pair over them (training would then take grey labels for colour
// ones), so it is an error unless they are all rewritten (--overwrite).
void RequireSameCameraPairOnResume(const std::string& summary_path, CameraPair pair, bool overwrite) {
  if (overwrite) return;
  const std::optional<CameraPair> made = RecordedCameraPair(summary_path);
  RequireFile(!made || *made == pair, summary_path,
              "the labels in this folder were made on the " + CameraPairName(made.value_or(pair)) +
                  " pair, this run reads the " + CameraPairName(pair) + " pair: pass --overwrite or another --out");
}

// A label file already in the output folder, read back for the summary: it must be a map of the
// sequence's images (a folder left over from another sequence or camera is an error naming the file,
// found before the odometry runs, not when its frame comes up hours later).
cv::Mat ReadExistingLabels(const std::string& path, int width, int height) {
  cv::Mat labels = ReadKittiMapPng(path);
  RequireFile(labels.cols == width && labels.rows == height, path,
              "existing label map is " + std::to_string(labels.cols) + "x" + std::to_string(labels.rows) +
                  ", the sequence's images are " + std::to_string(width) + "x" + std::to_string(height) +
                  " (left from another run? --overwrite replaces it)");
  return labels;
}

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

LabelRunSummary RunLabelExtraction(const std::string& sequence_dir, const std::string& out_dir,
                                   const LabelRunOptions& options) {
  options.Check();
  const auto sequence = OpenSequence(sequence_dir, "", options.cameras);
  Require(sequence->is_stereo(), sequence_dir + ": labels need a stereo sequence: " + sequence->NotStereoReason());
  for (const std::string& dir : {options.gt_disparity_dir, options.gt_disparity_right_dir}) {
    if (!dir.empty()) RequireFile(fs::is_directory(dir), dir, "ground-truth disparity folder does not exist");
  }
  Require(options.first < sequence->size(), sequence_dir + ": first frame beyond the sequence");
  const int end = RunEndFrame(sequence->size(), options.first, options.count);
  if (const std::string w = CountPastEndWarning(sequence->size(), options.first, options.count); !w.empty()) std::cerr << w << "\n";
  EnsureDirectory(out_dir);
  // A killed earlier run may have left a half-written map's temporary file; nothing reads it, but it
  // is no result either.
  RemoveUnfinishedAtomicWrites(out_dir);
  RemoveUnfinishedAtomicWrites(fs::path(LabelProducer::LabelPath(out_dir, 0, true)).parent_path().string());

  LabelRunSummary summary;
  summary.sequence = sequence_dir;
  summary.cameras = CameraPairName(sequence->camera_pair());
  summary.right_labels = options.labels.right_labels;
  // Label files already there (none count with overwrite): all of them = resume without running; some
  // = a partial resume, where LabelProducer keeps them (it writes only missing ones).
  std::vector<bool> kept(end - options.first, false), kept_right(end - options.first, false);
  bool complete = !options.labels.overwrite;
  for (int i = options.first; !options.labels.overwrite && i < end; ++i) {
    kept[i - options.first] = fs::exists(LabelProducer::LabelPath(out_dir, i));
    kept_right[i - options.first] = options.labels.right_labels && fs::exists(LabelProducer::LabelPath(out_dir, i, true));
    complete = complete && kept[i - options.first] && (!options.labels.right_labels || kept_right[i - options.first]);
  }
  const int width = sequence->camera().left.width, height = sequence->camera().left.height;
  RequireSameCameraPairOnResume(JoinPath(out_dir, "labels_summary.json"), sequence->camera_pair(),
                                options.labels.overwrite);
  // The first frame's ground truth is read now: a GT folder of another resolution (or without the
  // sequence's frame names) fails before the odometry runs, not at the first labelled frame minutes in.
  GroundTruth(options.gt_disparity_dir, options.first, width, height);
  GroundTruth(options.gt_disparity_right_dir, options.first, width, height);
  if (complete) {
    // Resume: every label file is there (written atomically, so complete); only re-read for the summary.
    summary.skipped_complete = true;
    for (int i = options.first; i < end; ++i) {
      summary.statistics.AddFrame(ReadExistingLabels(LabelProducer::LabelPath(out_dir, i), width, height),
                                  GroundTruth(options.gt_disparity_dir, i, width, height));
      if (options.labels.right_labels) {
        summary.right_statistics.AddFrame(
            ReadExistingLabels(LabelProducer::LabelPath(out_dir, i, true), width, height),
            GroundTruth(options.gt_disparity_right_dir, i, width, height));
      }
    }
  } else {
    // A partial resume: the statistics must describe the kept files, not the maps this run computed for them.
    summary.kept_existing_frames = static_cast<int>(std::count(kept.begin(), kept.end(), true));
    for (int i = options.first; i < end; ++i) {
      if (kept[i - options.first]) ReadExistingLabels(LabelProducer::LabelPath(out_dir, i), width, height);
      if (kept_right[i - options.first]) ReadExistingLabels(LabelProducer::LabelPath(out_dir, i, true), width, height);
    }
    const auto as_on_disk = [&](int frame_index, const cv::Mat& labels, bool right) {
      const std::vector<bool>& existed = right ? kept_right : kept;
      const int k = frame_index - options.first;
      return k >= 0 && k < static_cast<int>(existed.size()) && existed[k]
                 ? ReadExistingLabels(LabelProducer::LabelPath(out_dir, frame_index, right), width, height)
                 : labels;
    };
    PairCachingReader reader(*sequence, static_cast<size_t>(options.image_cache_pairs));
    double evaluation_ms = 0;
    LabelWriter writer(
        sequence->camera(), options.labels, out_dir,
        [&](int frame_index, const cv::Mat& labels) {
          const auto start = std::chrono::steady_clock::now();
          summary.statistics.AddFrame(as_on_disk(frame_index, labels, false),
                                      GroundTruth(options.gt_disparity_dir, frame_index, width, height));
          evaluation_ms += MsSince(start);
        },
        [&](int frame_index, cv::Mat* left, cv::Mat* right) { reader.Take(frame_index, left, right); },
        options.worker_thread,
        [&](int frame_index, const cv::Mat& labels) {
          const auto start = std::chrono::steady_clock::now();
          summary.right_statistics.AddFrame(as_on_disk(frame_index, labels, true),
                                            GroundTruth(options.gt_disparity_right_dir, frame_index, width, height));
          evaluation_ms += MsSince(start);
        });
    vo::SequenceRunOptions run;
    run.first = options.first;
    run.count = end - options.first;
    run.progress = options.progress;
    run.extra_observers.push_back(&writer);
    const auto start = std::chrono::steady_clock::now();
    const vo::SequenceRunSummary odometry =
        vo::RunOdometryOnSequence(reader, options.odometry, vo::OdometryMode::kStereo, JoinPath(out_dir, "odometry"), run);
    const double wall_ms = MsSince(start);
    const int frames = std::max(1, odometry.frames);
    const LabelCounters& counters = writer.counters();
    summary.labels_ms_per_frame = (counters.extract_ms + counters.write_ms) / frames;
    if (options.worker_thread) {
      // Labels run beside the odometry: the odometry's own time per frame, and
      // the wall time (without image decoding) for both together.
      summary.total_ms_per_frame = (wall_ms - reader.read_ms()) / frames;
      summary.odometry_ms_per_frame = odometry.mean_ms;
    } else {
      // One thread: wall time without image decoding and GT evaluation; the
      // writer's own time is split off as label time.
      summary.total_ms_per_frame = (wall_ms - reader.read_ms() - evaluation_ms) / frames;
      summary.odometry_ms_per_frame = summary.total_ms_per_frame - summary.labels_ms_per_frame;
    }
    summary.worker_thread = options.worker_thread;
    summary.image_read_ms_per_frame = reader.read_ms() / frames;
    summary.image_rereads = reader.rereads();
    summary.projected_labels = counters.projected;
    summary.verified_labels = counters.verified;
    summary.right_projected_labels = counters.right_projected;
    summary.right_verified_labels = counters.right_verified;
    summary.keyframes = odometry.keyframes;
    summary.lost = odometry.lost;
    Require(writer.frames_written() == end - options.first,
            sequence_dir + ": label writer finished " + std::to_string(writer.frames_written()) + " of " +
                std::to_string(end - options.first) + " frames");
  }
  const std::string json_path = JoinPath(out_dir, "labels_summary.json");
  WriteStreamAtomically(json_path, [&](std::ostream& out) { out << summary.ToJson().dump(2) << "\n"; });
  return summary;
}

std::vector<std::string> ReadSequenceList(const std::string& list_path) {
  std::ifstream in(list_path);
  RequireFile(in.good(), list_path, "cannot open sequence list");
  const fs::path base = fs::path(list_path).parent_path();
  std::vector<std::string> sequences;
  for (std::string line; std::getline(in, line);) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const auto last = line.find_last_not_of(" \t\r");
    fs::path p(line.substr(first, last - first + 1));
    if (p.is_relative()) p = base / p;
    sequences.push_back(p.string());
  }
  RequireFile(!sequences.empty(), list_path, "lists no sequences");
  return sequences;
}

}  // namespace dvso::labels
