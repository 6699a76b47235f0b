// `dvso labels`: stereo odometry over one or many sequences with a
// LabelWriter attached; resumable, with a summary per sequence and overall.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/sequence.h"
#include "sdso_labels/label_stats.h"
#include "sdso_labels/label_writer.h"
#include "vo/system/odometry_options.h"

namespace dvso::labels {

struct LabelRunOptions {
  LabelOptions labels;              // point filters and occlusion handling
  vo::OdometryOptions odometry;     // the stereo odometry (default preset)
  int first = 0;                    // first frame index of each sequence
  int count = -1;                   // frames per sequence (-1 = all)
  std::string gt_disparity_dir;     // optional GT disparity folder (%06d.png) for accuracy statistics
  std::string gt_disparity_right_dir;  // the same for right-image labels (e.g. the simulator's disp_1/)
  CameraPair cameras = CameraPair::kGrey;  // the stereo pair of a KITTI raw drive (grey 00/01 or colour 02/03)
  bool progress = true;             // progress bars on stderr
  // Produce labels on a worker thread beside the odometry. Off by default: on
  // the 2-core target the window optimisation already uses both cores (bench_labels).
  bool worker_thread = false;
  // Stereo pairs kept for the stereo check until their frame is labelled (~0.9 MB
  // each at KITTI size). Labelling lags the odometry by up to ~100 frames when a
  // keyframe stays in the window long; older pairs are decoded again (counted).
  int image_cache_pairs = 128;

  void Check() const;
};

// Loads `labels:` and `odometry:` sections (strict keys) plus an optional
// `preset:` (default|fast) for the odometry, `preset_without_key` when the file
// names none (`dvso labels --preset`); absent keys keep the defaults.
LabelRunOptions LoadLabelRunOptions(const std::string& path, const std::string& preset_without_key = "default");
std::string LabelRunOptionsToYaml(const LabelRunOptions& options);

struct LabelRunSummary {
  std::string sequence;
  // The stereo pair labelled ("grey" 00/01 or "colour" 02/03): training refuses labels of another pair
  // than the one it reads (stacknet/dataset.cpp).
  std::string cameras;
  bool skipped_complete = false;  // all label files existed: odometry not run (resume)
  // Partial resume: left label files that existed before the run and were kept (not rewritten
  // without labels.overwrite). The statistics describe the files on disk, so these frames are read
  // back; projected/verified_labels still count the maps this run computed.
  int kept_existing_frames = 0;
  // Timing (wall clock, image decoding excluded). One thread: odometry =
  // total - labels (GT evaluation excluded). Worker thread: odometry = the
  // System's own time per frame, total = wall time of both running side by
  // side (GT evaluation on the worker included).
  bool worker_thread = false;
  double odometry_ms_per_frame = 0;
  double labels_ms_per_frame = 0;      // label extraction (projection, stereo check) + PNG writing
  double total_ms_per_frame = 0;
  double image_read_ms_per_frame = 0;  // decoding the pair (the stereo check reuses it when cached)
  int image_rereads = 0;               // pairs decoded a second time (labelling lagged > the cache)
  long projected_labels = 0;           // labels before the stereo check (all frames)
  long verified_labels = 0;            // labels kept by it
  long right_projected_labels = 0, right_verified_labels = 0;  // the same, right image
  int keyframes = 0, lost = 0;         // of the odometry run
  LabelStatistics statistics;
  bool right_labels = false;
  LabelStatistics right_statistics;    // right-image labels (when written)

  nlohmann::json ToJson() const;
};

// Writes out_dir/%06d.png for every frame (and out_dir/right/%06d.png with
// labels.right_labels), out_dir/odometry/ (trajectory, run log, config) and
// out_dir/labels_summary.json.
LabelRunSummary RunLabelExtraction(const std::string& sequence_dir, const std::string& out_dir,
                                   const LabelRunOptions& options);

// Reads a batch list: one sequence directory per line ('#' comments, blank
// lines ignored; relative paths are relative to the list file).
std::vector<std::string> ReadSequenceList(const std::string& list_path);

}  // namespace dvso::labels
