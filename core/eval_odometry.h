// Odometry accuracy: the KITTI odometry benchmark protocol (t_rel, r_rel over
// 100..800 m segments, as the KITTI devkit's evaluate_odometry computes them),
// the absolute trajectory error (ATE) after Umeyama SE(3)/Sim(3) alignment and
// the relative pose error (RPE). Formulas: docs/evaluation.md.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/alignment.h"
#include "core/trajectory.h"

namespace dvso {

struct OdometryEvalOptions {
  // Alignment of the estimate onto the GT before every metric (ATE, RPE, t_rel/r_rel).
  AlignmentMode align = AlignmentMode::kNone;
  // KITTI segment lengths in metres (devkit: 100, 200, ..., 800).
  std::vector<double> segment_lengths = {100, 200, 300, 400, 500, 600, 700, 800};
  // A segment starts at every step_size-th GT frame (devkit: 10).
  int step_size = 10;
  // Largest timestamp difference (s) for a GT and an estimated pose to be paired.
  double max_time_difference = 0.01;
  // RPE frame distance: pairs (i, i + rpe_delta_frames) of GT frame indices.
  int rpe_delta_frames = 1;

  // Throws dvso::Error on invalid values.
  void Check() const;
};

// Mean errors of all KITTI segments of one length.
struct SegmentLengthErrors {
  double length = 0.0;     // metres
  int segments = 0;        // number of segments of this length evaluated
  double t_rel = 0.0;      // mean translation error, percent
  double r_rel = 0.0;      // mean rotation error, deg / 100 m
};

struct OdometryMetrics {
  AlignmentMode align = AlignmentMode::kNone;
  Similarity3 alignment;           // maps the estimate onto the GT (identity for kNone)
  int gt_frames = 0;               // poses in the GT
  int est_frames = 0;              // poses in the estimate
  int matched_frames = 0;          // GT poses with an associated estimated pose
  std::vector<int> missing_frames; // GT frame indices without an estimated pose
  std::vector<double> missing_timestamps;  // their GT timestamps (frame index for plain KITTI files)
  int unmatched_est_frames = 0;    // estimated poses matching no GT pose

  // KITTI protocol (on the aligned estimate when align != kNone).
  int segments = 0;                // segments of all lengths evaluated (0: see NoKittiSegmentsReason)
  int segments_without_estimate = 0;  // segments the GT path has but the estimate lacks a first or last pose of
  double t_rel = 0.0;              // mean over all segments of |t_err| / length, percent
  double r_rel = 0.0;              // mean over all segments of angle(R_err) / length, deg / 100 m
  std::vector<SegmentLengthErrors> per_length;

  // Absolute trajectory error over matched frames (after alignment), metres.
  double ate_rmse = 0.0, ate_mean = 0.0, ate_median = 0.0, ate_max = 0.0;

  // Relative pose error over GT frame pairs (i, i + rpe_delta_frames), both matched.
  int rpe_delta_frames = 1;
  int rpe_pairs = 0;
  double rpe_trans_rmse = 0.0;     // metres
  double rpe_trans_mean = 0.0;     // metres
  double rpe_rot_rmse = 0.0;       // degrees
  double rpe_rot_mean = 0.0;       // degrees

  double gt_path_length = 0.0;     // metres, over all GT frames
  double est_path_length = 0.0;    // metres, aligned estimate over matched frames
};

// Pairs every GT pose with an estimated pose by timestamp (KITTI files without
// times carry their frame index as timestamp, so this is association by index).
// Returns, per GT index, the estimate index or -1. Candidates within
// max_time_difference are taken greedily by increasing time difference; each
// estimated pose is used at most once. Timestamps must increase strictly.
std::vector<int> AssociateByTimestamp(const Trajectory& gt, const Trajectory& est,
                                      double max_time_difference);

// KITTI devkit segment errors on two equally long, already associated pose
// lists (gt[i] <-> est[i]); `valid[i]` false skips segments touching frame i.
// Distances come from the full GT path. Fills t_rel, r_rel, segments, per_length.
void ComputeKittiSegmentErrors(const std::vector<Eigen::Isometry3d>& gt,
                               const std::vector<Eigen::Isometry3d>& est, const std::vector<bool>& valid,
                               const OdometryEvalOptions& options, OdometryMetrics* metrics);

// Why `metrics` has no KITTI segment (for segments == 0): every segment the GT path has was dropped because
// the estimate lacks its first or last frame, or the GT path is no longer than the shortest segment length.
std::string NoKittiSegmentsReason(const OdometryMetrics& metrics);

// Full evaluation. Throws dvso::Error when fewer than 2 frames match (3 with alignment).
OdometryMetrics EvaluateOdometry(const Trajectory& gt, const Trajectory& est,
                                 const OdometryEvalOptions& options);

// The estimate after the alignment found by EvaluateOdometry, restricted to
// frames matched to the GT, in GT order (for plots / export).
Trajectory AlignedMatchedEstimate(const Trajectory& gt, const Trajectory& est,
                                  const OdometryEvalOptions& options, const OdometryMetrics& metrics);

// One JSON object with every metric (undefined metrics, e.g. t_rel without
// segments, are null).
nlohmann::json OdometryMetricsToJson(const OdometryMetrics& metrics);

// Human-readable multi-line table.
std::string FormatOdometryMetrics(const OdometryMetrics& metrics);

// Writes <dir>/trajectory_xz.png (top view, GT vs aligned estimate) and, when
// any KITTI segment was evaluated, <dir>/segment_errors.png (t_rel and r_rel per
// segment length); without segments an old segment_errors.png is removed, so the
// folder never shows another run's errors. Returns the paths written.
std::vector<std::string> WriteOdometryPlots(const std::string& dir, const Trajectory& gt, const Trajectory& aligned_est,
                        const OdometryMetrics& metrics);

}  // namespace dvso
