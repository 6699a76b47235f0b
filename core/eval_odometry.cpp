#include "core/eval_odometry.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "core/error.h"
#include "core/lie.h"
#include "core/statistics.h"

namespace dvso {

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

void RequireIncreasingTimestamps(const Trajectory& trajectory, const std::string& name) {
  for (size_t i = 1; i < trajectory.size(); ++i) {
    Require(trajectory.poses[i].timestamp > trajectory.poses[i - 1].timestamp,
            name + " timestamps must increase strictly: pose " + std::to_string(i) + " has " +
                std::to_string(trajectory.poses[i].timestamp) + " after " +
                std::to_string(trajectory.poses[i - 1].timestamp));
  }
}

// Devkit trajectoryDistances: cumulative GT path length up to each frame.
std::vector<double> CumulativeDistances(const std::vector<Eigen::Isometry3d>& poses) {
  std::vector<double> distances(poses.size(), 0.0);
  for (size_t i = 1; i < poses.size(); ++i) {
    distances[i] = distances[i - 1] + (poses[i].translation() - poses[i - 1].translation()).norm();
  }
  return distances;
}

// Devkit lastFrameFromSegmentLength: first frame whose distance exceeds
// distance(first) + length strictly; -1 if the path is too short.
int LastFrameOfSegment(const std::vector<double>& distances, int first, double length) {
  for (size_t i = static_cast<size_t>(first); i < distances.size(); ++i) {
    if (distances[i] > distances[first] + length) return static_cast<int>(i);
  }
  return -1;
}

// The devkit's pose error inv(inv(est_a) est_b) * (inv(gt_a) gt_b), with
// general 4x4 inverses as in the devkit: KITTI files store rotations with 6-7
// significant digits, and a transpose-as-inverse would turn that
// non-orthogonality into a spurious ~0.007 deg/100 m rotation error (GT vs GT).
Eigen::Matrix4d RelativePoseError(const Eigen::Isometry3d& gt_a, const Eigen::Isometry3d& gt_b,
                                  const Eigen::Isometry3d& est_a, const Eigen::Isometry3d& est_b) {
  const Eigen::Matrix4d delta_gt = gt_a.matrix().inverse() * gt_b.matrix();
  const Eigen::Matrix4d delta_est = est_a.matrix().inverse() * est_b.matrix();
  return delta_est.inverse() * delta_gt;
}

}  // namespace

void OdometryEvalOptions::Check() const {
  Require(!segment_lengths.empty(), "eval-odometry: segment_lengths must not be empty");
  for (const double length : segment_lengths) {
    Require(std::isfinite(length) && length > 0.0, "eval-odometry: segment lengths must be positive");
  }
  Require(step_size >= 1, "eval-odometry: step_size must be >= 1");
  Require(std::isfinite(max_time_difference) && max_time_difference >= 0.0,
          "eval-odometry: max_time_difference must be >= 0");
  Require(rpe_delta_frames >= 1, "eval-odometry: rpe_delta_frames must be >= 1");
}

std::vector<int> AssociateByTimestamp(const Trajectory& gt, const Trajectory& est,
                                      double max_time_difference) {
  RequireIncreasingTimestamps(gt, "ground-truth");
  RequireIncreasingTimestamps(est, "estimated");
  struct Candidate {
    double difference;
    int gt_index, est_index;
  };
  std::vector<Candidate> candidates;
  std::vector<double> est_times(est.size());
  for (size_t j = 0; j < est.size(); ++j) est_times[j] = est.poses[j].timestamp;
  for (size_t i = 0; i < gt.size(); ++i) {
    const double t = gt.poses[i].timestamp;
    auto it = std::lower_bound(est_times.begin(), est_times.end(), t - max_time_difference);
    for (; it != est_times.end() && *it <= t + max_time_difference; ++it) {
      candidates.push_back({std::abs(*it - t), static_cast<int>(i), static_cast<int>(it - est_times.begin())});
    }
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.difference < b.difference; });
  std::vector<int> match(gt.size(), -1);
  std::vector<bool> est_used(est.size(), false);
  for (const Candidate& c : candidates) {
    if (match[c.gt_index] >= 0 || est_used[c.est_index]) continue;
    match[c.gt_index] = c.est_index;
    est_used[c.est_index] = true;
  }
  return match;
}

void ComputeKittiSegmentErrors(const std::vector<Eigen::Isometry3d>& gt,
                               const std::vector<Eigen::Isometry3d>& est, const std::vector<bool>& valid,
                               const OdometryEvalOptions& options, OdometryMetrics* metrics) {
  Require(gt.size() == est.size() && gt.size() == valid.size(),
          "KITTI segment errors need equally long GT, estimate and validity lists");
  const std::vector<double> distances = CumulativeDistances(gt);
  metrics->per_length.clear();
  for (const double length : options.segment_lengths) metrics->per_length.push_back({length, 0, 0.0, 0.0});
  double sum_t = 0.0, sum_r = 0.0;
  int count = 0;
  metrics->segments_without_estimate = 0;
  for (size_t first = 0; first < gt.size(); first += static_cast<size_t>(options.step_size)) {
    for (size_t l = 0; l < options.segment_lengths.size(); ++l) {
      const double length = options.segment_lengths[l];
      const int last = LastFrameOfSegment(distances, static_cast<int>(first), length);
      if (last < 0) continue;
      if (!valid[first] || !valid[last]) {  // estimate lacks an end pose of this segment
        ++metrics->segments_without_estimate;
        continue;
      }
      const Eigen::Matrix4d error = RelativePoseError(gt[first], gt[last], est[first], est[last]);
      // Per-metre errors, as the devkit stores them (rad/m and m/m).
      const double r_err = RotationAngle(error.topLeftCorner<3, 3>()) / length;
      const double t_err = error.topRightCorner<3, 1>().norm() / length;
      sum_t += t_err;
      sum_r += r_err;
      ++count;
      SegmentLengthErrors& bucket = metrics->per_length[l];
      bucket.segments += 1;
      bucket.t_rel += t_err;
      bucket.r_rel += r_err;
    }
  }
  // Report as the benchmark tables do: t in percent, r in degrees per 100 m.
  metrics->segments = count;
  metrics->t_rel = count > 0 ? 100.0 * sum_t / count : std::numeric_limits<double>::quiet_NaN();
  metrics->r_rel = count > 0 ? 100.0 * kRadToDeg * sum_r / count : std::numeric_limits<double>::quiet_NaN();
  for (SegmentLengthErrors& bucket : metrics->per_length) {
    if (bucket.segments == 0) {
      bucket.t_rel = bucket.r_rel = std::numeric_limits<double>::quiet_NaN();
    } else {
      bucket.t_rel = 100.0 * bucket.t_rel / bucket.segments;
      bucket.r_rel = 100.0 * kRadToDeg * bucket.r_rel / bucket.segments;
    }
  }
}

std::string NoKittiSegmentsReason(const OdometryMetrics& metrics) {
  if (metrics.segments_without_estimate > 0) {
    return "the estimate lacks the first or last frame of all " + std::to_string(metrics.segments_without_estimate) +
           " segments of the GT path";
  }
  return "the GT path is no longer than the shortest segment length";
}

namespace {

struct Associated {
  std::vector<int> match;                 // per GT frame: estimate index or -1
  std::vector<Eigen::Vector3d> gt_xyz;    // matched positions, GT order
  std::vector<Eigen::Vector3d> est_xyz;
};

Associated Associate(const Trajectory& gt, const Trajectory& est, const OdometryEvalOptions& options) {
  Require(!gt.empty(), "ground-truth trajectory is empty");
  Require(!est.empty(), "estimated trajectory is empty");
  Associated a;
  a.match = AssociateByTimestamp(gt, est, options.max_time_difference);
  for (size_t i = 0; i < gt.size(); ++i) {
    if (a.match[i] < 0) continue;
    a.gt_xyz.push_back(gt.poses[i].T_world_camera.translation());
    a.est_xyz.push_back(est.poses[a.match[i]].T_world_camera.translation());
  }
  // Fewer than half of the estimate paired means two time bases that meet by chance (a KITTI file
  // without --gt-times is timed by frame index 0, 1, 2, ..., a TUM file by seconds): the numbers of such
  // a pairing describe nothing.
  const size_t needed = std::max<size_t>(2, (std::min(gt.size(), est.size()) + 1) / 2);
  Require(a.gt_xyz.size() >= needed,
          "only " + std::to_string(a.gt_xyz.size()) + " of " + std::to_string(est.size()) +
              " estimated poses match a ground-truth pose (by timestamp within " +
              std::to_string(options.max_time_difference) +
              " s; KITTI files without times match by frame index, TUM files by seconds: give --gt-times / "
              "--est-times times.txt for a KITTI file beside a TUM one): check that both files describe the same "
              "sequence and use the same time base");
  return a;
}

}  // namespace

OdometryMetrics EvaluateOdometry(const Trajectory& gt, const Trajectory& est,
                                 const OdometryEvalOptions& options) {
  options.Check();
  const Associated a = Associate(gt, est, options);
  OdometryMetrics m;
  m.align = options.align;
  m.gt_frames = static_cast<int>(gt.size());
  m.est_frames = static_cast<int>(est.size());
  m.matched_frames = static_cast<int>(a.gt_xyz.size());
  for (size_t i = 0; i < gt.size(); ++i) {
    if (a.match[i] >= 0) continue;
    m.missing_frames.push_back(static_cast<int>(i));
    m.missing_timestamps.push_back(gt.poses[i].timestamp);
  }
  m.unmatched_est_frames = m.est_frames - m.matched_frames;
  m.alignment = UmeyamaAlignment(a.est_xyz, a.gt_xyz, options.align);
  m.gt_path_length = gt.PathLength();

  // Aligned estimate on the GT frame grid (identity where missing).
  std::vector<Eigen::Isometry3d> gt_poses(gt.size()), est_poses(gt.size(), Eigen::Isometry3d::Identity());
  std::vector<bool> valid(gt.size(), false);
  for (size_t i = 0; i < gt.size(); ++i) {
    gt_poses[i] = gt.poses[i].T_world_camera;
    if (a.match[i] < 0) continue;
    est_poses[i] = m.alignment.Apply(est.poses[a.match[i]].T_world_camera);
    valid[i] = true;
  }

  ComputeKittiSegmentErrors(gt_poses, est_poses, valid, options, &m);

  // ATE: position differences after alignment.
  std::vector<double> ate;
  bool has_previous = false;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < gt.size(); ++i) {
    if (!valid[i]) continue;
    const Eigen::Vector3d p = est_poses[i].translation();
    ate.push_back((gt_poses[i].translation() - p).norm());
    if (has_previous) m.est_path_length += (p - previous).norm();
    previous = p;
    has_previous = true;
  }
  double sum_sq = 0.0, sum = 0.0;
  for (const double e : ate) {
    sum_sq += e * e;
    sum += e;
    m.ate_max = std::max(m.ate_max, e);
  }
  m.ate_rmse = std::sqrt(sum_sq / ate.size());
  m.ate_mean = sum / ate.size();
  m.ate_median = ate.empty() ? 0.0 : Median(ate);

  // RPE over GT frame pairs (i, i + delta), the TUM RGB-D benchmark's relative pose error.
  m.rpe_delta_frames = options.rpe_delta_frames;
  double t_sq = 0.0, t_sum = 0.0, r_sq = 0.0, r_sum = 0.0;
  for (size_t i = 0; i + options.rpe_delta_frames < gt.size(); ++i) {
    const size_t j = i + options.rpe_delta_frames;
    if (!valid[i] || !valid[j]) continue;
    // TUM's E = (gt_i^-1 gt_j)^-1 (est_i^-1 est_j) is the inverse of the devkit's
    // (est_i^-1 est_j)^-1 (gt_i^-1 gt_j); both have the same angle and the
    // translation norms differ only by a rotation, so one helper serves both.
    const Eigen::Matrix4d error = RelativePoseError(gt_poses[i], gt_poses[j], est_poses[i], est_poses[j]);
    const double t = error.topRightCorner<3, 1>().norm();
    const double r = RotationAngle(error.topLeftCorner<3, 3>()) * kRadToDeg;
    t_sq += t * t;
    t_sum += t;
    r_sq += r * r;
    r_sum += r;
    ++m.rpe_pairs;
  }
  if (m.rpe_pairs > 0) {
    m.rpe_trans_rmse = std::sqrt(t_sq / m.rpe_pairs);
    m.rpe_trans_mean = t_sum / m.rpe_pairs;
    m.rpe_rot_rmse = std::sqrt(r_sq / m.rpe_pairs);
    m.rpe_rot_mean = r_sum / m.rpe_pairs;
  } else {
    m.rpe_trans_rmse = m.rpe_trans_mean = m.rpe_rot_rmse = m.rpe_rot_mean =
        std::numeric_limits<double>::quiet_NaN();
  }
  return m;
}

Trajectory AlignedMatchedEstimate(const Trajectory& gt, const Trajectory& est,
                                  const OdometryEvalOptions& options, const OdometryMetrics& metrics) {
  const std::vector<int> match = AssociateByTimestamp(gt, est, options.max_time_difference);
  Trajectory aligned;
  for (size_t i = 0; i < gt.size(); ++i) {
    if (match[i] < 0) continue;
    StampedPose pose = est.poses[match[i]];
    pose.T_world_camera = metrics.alignment.Apply(pose.T_world_camera);
    aligned.poses.push_back(pose);
  }
  return aligned;
}

namespace {

nlohmann::json NumberOrNull(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

std::string FormatNumber(double value, int precision, const std::string& unit) {
  if (!std::isfinite(value)) return "n/a";
  std::ostringstream out;
  out << std::fixed << std::setprecision(precision) << value << unit;
  return out.str();
}

std::string KittiBasis(AlignmentMode align) {
  return align == AlignmentMode::kNone ? "raw estimate (no alignment)"
                                       : AlignmentModeName(align) + "-aligned estimate";
}

}  // namespace

nlohmann::json OdometryMetricsToJson(const OdometryMetrics& m) {
  nlohmann::json j;
  j["align"] = AlignmentModeName(m.align);
  j["kitti_metrics_on"] = KittiBasis(m.align);
  j["t_rel"] = NumberOrNull(m.t_rel);
  j["r_rel"] = NumberOrNull(m.r_rel);
  j["t_rel_unit"] = "percent";
  j["r_rel_unit"] = "deg/100m";
  j["segments"] = m.segments;
  j["segments_without_estimate"] = m.segments_without_estimate;
  nlohmann::json per_length = nlohmann::json::array();
  for (const SegmentLengthErrors& b : m.per_length) {
    per_length.push_back({{"length", b.length}, {"segments", b.segments}, {"t_rel", NumberOrNull(b.t_rel)},
                          {"r_rel", NumberOrNull(b.r_rel)}});
  }
  j["per_length"] = per_length;
  j["ate_rmse"] = m.ate_rmse;
  j["ate_mean"] = m.ate_mean;
  j["ate_median"] = m.ate_median;
  j["ate_max"] = m.ate_max;
  j["scale"] = m.alignment.scale;
  const Eigen::Quaterniond q(m.alignment.rotation);
  j["alignment"] = {{"scale", m.alignment.scale},
                    {"rotation_xyzw", {q.x(), q.y(), q.z(), q.w()}},
                    {"translation", {m.alignment.translation.x(), m.alignment.translation.y(),
                                     m.alignment.translation.z()}}};
  j["rpe_delta_frames"] = m.rpe_delta_frames;
  j["rpe_pairs"] = m.rpe_pairs;
  j["rpe_trans_rmse"] = NumberOrNull(m.rpe_trans_rmse);
  j["rpe_trans_mean"] = NumberOrNull(m.rpe_trans_mean);
  j["rpe_rot_rmse_deg"] = NumberOrNull(m.rpe_rot_rmse);
  j["rpe_rot_mean_deg"] = NumberOrNull(m.rpe_rot_mean);
  j["frames"] = m.gt_frames;
  j["est_frames"] = m.est_frames;
  j["matched_frames"] = m.matched_frames;
  j["missing_frames"] = m.missing_frames.size();
  j["missing_frame_indices"] = m.missing_frames;
  j["missing_frame_timestamps"] = m.missing_timestamps;
  j["unmatched_est_frames"] = m.unmatched_est_frames;
  j["gt_path_length"] = m.gt_path_length;
  j["est_path_length"] = m.est_path_length;
  return j;
}

namespace {

// "3-5, 9, 12-20": compact list of sorted frame indices (first `max_runs` runs).
std::string FormatIndexRuns(const std::vector<int>& indices, size_t max_runs = 12) {
  std::ostringstream out;
  size_t runs = 0;
  for (size_t i = 0; i < indices.size();) {
    size_t j = i;
    while (j + 1 < indices.size() && indices[j + 1] == indices[j] + 1) ++j;
    if (runs == max_runs) {
      out << ", ... (" << indices.size() - i << " more)";
      break;
    }
    if (runs > 0) out << ", ";
    out << indices[i];
    if (j > i) out << "-" << indices[j];
    ++runs;
    i = j + 1;
  }
  return out.str();
}

}  // namespace

std::string FormatOdometryMetrics(const OdometryMetrics& m) {
  std::ostringstream out;
  out << "frames            : " << m.gt_frames << " GT, " << m.est_frames << " estimated, "
      << m.matched_frames << " matched\n";
  out << "missing frames    : " << m.missing_frames.size();
  if (!m.missing_frames.empty()) out << " (GT indices " << FormatIndexRuns(m.missing_frames) << ")";
  out << "\n";
  if (m.unmatched_est_frames > 0) {
    out << "unmatched estimate: " << m.unmatched_est_frames << " poses match no GT pose\n";
  }
  out << "alignment         : " << AlignmentModeName(m.align);
  if (m.align == AlignmentMode::kSim3) out << " (scale " << FormatNumber(m.alignment.scale, 6, "") << ")";
  out << "\n";
  out << "path length       : GT " << FormatNumber(m.gt_path_length, 2, " m") << ", estimate "
      << FormatNumber(m.est_path_length, 2, " m") << "\n";
  out << "KITTI (" << KittiBasis(m.align) << ", " << m.segments << " segments):\n";
  out << "  t_rel           : " << FormatNumber(m.t_rel, 4, " %") << "\n";
  out << "  r_rel           : " << FormatNumber(m.r_rel, 4, " deg/100m") << "\n";
  if (m.segments == 0) out << "  (no KITTI segments: " << NoKittiSegmentsReason(m) << ")\n";
  for (const SegmentLengthErrors& b : m.per_length) {
    if (b.segments == 0) continue;
    out << "    " << std::setw(5) << b.length << " m  (" << std::setw(5) << b.segments << " segs): t "
        << FormatNumber(b.t_rel, 4, " %") << ", r " << FormatNumber(b.r_rel, 4, " deg/100m") << "\n";
  }
  out << "ATE (" << (m.align == AlignmentMode::kNone ? "unaligned" : AlignmentModeName(m.align) + "-aligned")
      << ")    : rmse " << FormatNumber(m.ate_rmse, 4, " m") << ", mean " << FormatNumber(m.ate_mean, 4, " m")
      << ", median " << FormatNumber(m.ate_median, 4, " m") << ", max " << FormatNumber(m.ate_max, 4, " m")
      << "\n";
  out << "RPE (" << m.rpe_delta_frames << " frame" << (m.rpe_delta_frames == 1 ? "" : "s") << ", "
      << m.rpe_pairs << " pairs): trans rmse " << FormatNumber(m.rpe_trans_rmse, 4, " m") << ", rot rmse "
      << FormatNumber(m.rpe_rot_rmse, 4, " deg") << "\n";
  return out.str();
}

}  // namespace dvso
