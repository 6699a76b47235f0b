#include "core/simulator_path.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

#include <Eigen/Sparse>

#include "core/error.h"
#include "core/lie.h"

namespace dvso::sim {
namespace {

// The camera centres split along `down`: heights, horizontal positions and horizontal arc lengths.
struct CameraTrack {
  std::vector<double> height, s;
  std::vector<Eigen::Vector3d> flat;
};

CameraTrack TrackOf(const std::vector<Eigen::Isometry3d>& poses, const Eigen::Vector3d& down) {
  const int n = static_cast<int>(poses.size());
  CameraTrack track;
  track.height.resize(n);
  track.flat.resize(n);
  track.s.assign(n, 0.0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = poses[i].translation();
    track.height[i] = p.dot(down);
    track.flat[i] = p - track.height[i] * down;
    if (i > 0) track.s[i] = track.s[i - 1] + (track.flat[i] - track.flat[i - 1]).norm();
  }
  return track;
}

}  // namespace

HorizontalGrid::HorizontalGrid(const Eigen::Vector3d& down, double cell_size)
    : axis_a_(down.unitOrthogonal()), axis_b_(down.cross(axis_a_)), cell_size_(cell_size) {
  Require(cell_size > 0, "horizontal grid: the cell size must be > 0");
}

std::pair<int, int> HorizontalGrid::CellOf(const Eigen::Vector3d& q) const {
  return {static_cast<int>(std::floor(q.dot(axis_a_) / cell_size_)),
          static_cast<int>(std::floor(q.dot(axis_b_) / cell_size_))};
}

void HorizontalGrid::Insert(const Eigen::Vector3d& q, int index) {
  const std::pair<int, int> cell = CellOf(q);
  cells_[Key(cell.first, cell.second)].push_back(index);
}

StreetPath::StreetPath(const std::vector<Eigen::Isometry3d>& poses, double camera_height, double spacing,
                       double extension)
    : spacing_(spacing) {
  Require(!poses.empty(), "the simulator needs at least one pose");
  Require(spacing > 0.1, "path sample spacing must be > 0.1 m");
  down_ = TrajectoryDown(poses);
  grid_ = HorizontalGrid(down_, kGridCellSize);

  // Horizontal positions, heights and arc lengths of the camera centres.
  const int n = static_cast<int>(poses.size());
  CameraTrack track = TrackOf(poses, down_);
  const std::vector<Eigen::Vector3d>& flat = track.flat;
  const std::vector<double>& height = track.height;
  pose_s_ = std::move(track.s);
  const double total = pose_s_.back();
  // Driving direction at the ends: from positions 5 m apart, or the camera's
  // optical axis when the camera hardly moves.
  auto end_direction = [&](bool at_end) {
    const int i = at_end ? n - 1 : 0;
    const double target = at_end ? total - 5.0 : 5.0;
    int j = i;
    if (total > 1.0) {
      j = static_cast<int>(std::lower_bound(pose_s_.begin(), pose_s_.end(), target) - pose_s_.begin());
      j = std::clamp(j, 0, n - 1);
    }
    Eigen::Vector3d d = at_end ? flat[i] - flat[j] : flat[j] - flat[i];
    if (d.norm() < 0.5) d = poses[i].linear().col(2) - poses[i].linear().col(2).dot(down_) * down_;
    return Eigen::Vector3d(d.normalized());
  };
  const Eigen::Vector3d dir_begin = end_direction(false), dir_end = end_direction(true);

  auto position_at = [&](double s, double* h) -> Eigen::Vector3d {
    if (s <= 0) {
      *h = height[0];
      return flat[0] + s * dir_begin;
    }
    if (s >= total) {
      *h = height[n - 1];
      return flat[n - 1] + (s - total) * dir_end;
    }
    const int k = static_cast<int>(std::upper_bound(pose_s_.begin(), pose_s_.end(), s) - pose_s_.begin());
    const int a = std::max(k - 1, 0), b = std::min(k, n - 1);
    const double len = pose_s_[b] - pose_s_[a];
    const double t = len > 1e-9 ? (s - pose_s_[a]) / len : 0.0;
    *h = height[a] + t * (height[b] - height[a]);
    return flat[a] + t * (flat[b] - flat[a]);
  };

  const int before = static_cast<int>(std::ceil(extension / spacing));
  const int count = before + static_cast<int>(std::ceil((total + extension) / spacing)) + 1;
  std::vector<Eigen::Vector3d> centre(count);
  std::vector<double> h(count);
  samples_.resize(count);
  for (int j = 0; j < count; ++j) {
    samples_[j].s = (j - before) * spacing;
    centre[j] = position_at(samples_[j].s, &h[j]);
  }
  // The road follows the path's height, smoothed over ~+-8 m so that the
  // vehicle's pitching does not turn into bumps.
  const int half = std::max(1, static_cast<int>(std::round(8.0 / spacing)));
  for (int j = 0; j < count; ++j) {
    double sum = 0, weight = 0;
    for (int k = std::max(0, j - half); k <= std::min(count - 1, j + half); ++k) {
      const double w = 1.0 + half - std::abs(k - j);
      sum += w * h[k];
      weight += w;
    }
    PathSample& sample = samples_[j];
    sample.road = centre[j] + (sum / weight + camera_height) * down_;
    const Eigen::Vector3d d = centre[std::min(j + 1, count - 1)] - centre[std::max(j - 1, 0)];
    sample.tangent = d.norm() > 1e-9 ? d.normalized() : dir_begin;
    sample.right = down_.cross(sample.tangent).normalized();
  }
  for (int j = 0; j < count; ++j) grid_.Insert(samples_[j].road, j);
}

int StreetPath::SampleAt(double s) const {
  const double first = samples_.front().s;
  const int j = static_cast<int>(std::lround((s - first) / spacing_));
  return std::clamp(j, 0, static_cast<int>(samples_.size()) - 1);
}

bool StreetPath::InZone(const Eigen::Vector3d& q, Zone zone, double margin, double object_height) const {
  return AnySampleZoneContains(q, zone, margin, /*ignore_begin=*/0, /*ignore_end=*/0, object_height);
}

bool StreetPath::InZoneOfOtherSamples(const Eigen::Vector3d& q, Zone zone, double margin, int ignore_begin,
                                      int ignore_end) const {
  return AnySampleZoneContains(q, zone, margin, ignore_begin, ignore_end, /*object_height=*/0.0);
}

bool StreetPath::AnySampleZoneContains(const Eigen::Vector3d& q, Zone zone, double margin, int ignore_begin,
                                       int ignore_end, double object_height) const {
  return grid_.AnyNear(q, [&](int j) {
    if (j >= ignore_begin && j < ignore_end) return false;
    const PathSample& sample = samples_[j];
    if (sample.merged_into >= 0 && zone != Zone::kLane) return false;
    const Eigen::Vector3d d = q - sample.road;
    // Height of q above this sample's road; the object spans [above, above + object_height].
    const double above = -d.dot(down_);
    if (above > kLevelClearance || above + object_height < -kLevelClearance) return false;  // over- or underpass
    if (std::abs(d.dot(sample.tangent)) > 0.75 * spacing_ + 0.1) return false;
    const double lateral = d.dot(sample.right);
    const StreetProfile& p = sample.profile;
    double lo = -1.6, hi = 1.6;
    if (zone == Zone::kRoad) {
      lo = p.left_edge;
      hi = p.right_edge;
    } else if (zone == Zone::kStreet) {
      lo = p.left_edge - p.sidewalk_left;
      hi = p.right_edge + p.sidewalk_right;
    }
    return lateral > lo - margin && lateral < hi + margin;
  });
}

void StreetPath::DropExtensionsOverThePath(double radius, double min_gap) {
  Require(radius > 0 && radius <= grid_.cell_size(),
          "invented streets: the yield radius must be in (0, " + std::to_string(std::lround(grid_.cell_size())) + "] m");
  const double total = pose_s_.back();
  for (PathSample& e : samples_) {
    if (e.s >= 0 && e.s <= total) continue;  // a sample of the driven path
    int nearest = -1;
    double nearest_distance = radius;
    grid_.AnyNear(e.road, [&](int i) {
      const PathSample& r = samples_[i];
      if (r.s < 0 || r.s > total || std::abs(r.s - e.s) < min_gap) return false;
      const Eigen::Vector3d d = r.road - e.road;
      const double distance = (d - d.dot(down_) * down_).norm();
      if (distance < nearest_distance) {
        nearest_distance = distance;
        nearest = i;
      }
      return false;
    });
    if (nearest >= 0) e.merged_into = nearest;
  }
}

void StreetPath::MergeRevisits(double radius, double min_gap) {
  Require(radius > 0 && radius <= grid_.cell_size(),
          "revisits: the merge radius must be in (0, " + std::to_string(std::lround(grid_.cell_size())) + "] m");
  const int n = static_cast<int>(samples_.size());
  for (int j = 0; j < n; ++j) {
    PathSample& b = samples_[j];
    if (b.merged_into >= 0) continue;  // a dropped extension (DropExtensionsOverThePath)
    int best = -1;
    double best_distance = radius;
    grid_.AnyNear(b.road, [&](int i) {
      const PathSample& a = samples_[i];
      if (i >= j || b.s - a.s < min_gap || a.merged_into >= 0) return false;
      const Eigen::Vector3d d = b.road - a.road;
      if (std::abs(d.dot(down_)) > 2.0 || std::abs(a.tangent.dot(b.tangent)) < 0.85) return false;
      const double distance = (d - d.dot(down_) * down_).norm();
      if (distance < best_distance) {
        best_distance = distance;
        best = i;
      }
      return false;
    });
    if (best < 0) continue;
    b.merged_into = best;
    // Widen the earlier street so that the revisit's lane (+-2 m) is road.
    for (int k = std::max(0, best - 2); k <= std::min(n - 1, best + 2); ++k) {
      StreetProfile& p = samples_[k].profile;
      const double lateral = (b.road - samples_[k].road).dot(samples_[k].right);
      p.left_edge = std::min(p.left_edge, lateral - 2.0);
      p.right_edge = std::max(p.right_edge, lateral + 2.0);
    }
  }
  // Spread the widening over +-3 samples, so that curbs run smoothly.
  std::vector<double> left(n), right(n);
  for (int j = 0; j < n; ++j) {
    left[j] = samples_[j].profile.left_edge;
    right[j] = samples_[j].profile.right_edge;
    for (int k = std::max(0, j - 3); k <= std::min(n - 1, j + 3); ++k) {
      left[j] = std::min(left[j], samples_[k].profile.left_edge);
      right[j] = std::max(right[j], samples_[k].profile.right_edge);
    }
  }
  for (int j = 0; j < n; ++j) {
    samples_[j].profile.left_edge = left[j];
    samples_[j].profile.right_edge = right[j];
  }
}

Eigen::Vector3d TrajectoryDown(const std::vector<Eigen::Isometry3d>& poses) {
  Eigen::Vector3d down = Eigen::Vector3d::Zero();
  for (const auto& T : poses) down += T.linear().col(1);
  Require(down.norm() > 1e-6, "cannot determine the down direction of the trajectory");
  return down.normalized();
}

void AltitudeReconciliationOptions::Check() const {
  // Beyond ~50 m, pairs would join parallel streets of a town, not one street seen twice.
  Require(radius > 0 && radius < 50, "altitude reconciliation: radius must be in (0, 50) m");
  Require(min_gap > 2 * radius, "altitude reconciliation: min_gap must exceed twice the radius");
  Require(max_difference > 0, "altitude reconciliation: max_difference must be > 0");
  Require(smoothness > 0, "altitude reconciliation: smoothness must be > 0");
  Require(spacing > 0.1 && spacing <= radius, "altitude reconciliation: spacing must be in (0.1, radius] m");
}

std::vector<AltitudeCorrection> AltitudeCorrections(const std::vector<Eigen::Isometry3d>& poses,
                                                    const AltitudeReconciliationOptions& options) {
  options.Check();
  const int num_poses = static_cast<int>(poses.size());
  std::vector<AltitudeCorrection> corrections(num_poses);
  if (num_poses < 2) return corrections;
  const Eigen::Vector3d down = TrajectoryDown(poses);
  const CameraTrack track = TrackOf(poses, down);
  const std::vector<double>& height = track.height;
  const std::vector<double>& pose_s = track.s;
  const std::vector<Eigen::Vector3d>& flat = track.flat;
  // Samples every `spacing` m of arc length (linear interpolation between poses).
  const int n = static_cast<int>(std::floor(pose_s.back() / options.spacing)) + 1;
  if (n < 3) return corrections;
  std::vector<Eigen::Vector3d> sample_flat(n);
  std::vector<double> sample_height(n);
  for (int k = 0, i = 0; k < n; ++k) {
    const double s = k * options.spacing;
    while (i + 2 < num_poses && pose_s[i + 1] < s) ++i;
    const double len = pose_s[i + 1] - pose_s[i];
    const double t = len > 1e-9 ? std::clamp((s - pose_s[i]) / len, 0.0, 1.0) : 0.0;
    sample_flat[k] = flat[i] + t * (flat[i + 1] - flat[i]);
    sample_height[k] = height[i] + t * (height[i + 1] - height[i]);
  }
  // Pairs of samples on the same street from different passes (grid cell = radius).
  HorizontalGrid grid(down, options.radius);
  for (int k = 0; k < n; ++k) grid.Insert(sample_flat[k], k);
  std::vector<Eigen::Triplet<double>> normal;  // normal equations A^T A (summed by setFromTriplets)
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  int pairs = 0;
  for (int k = 0; k < n; ++k) {
    grid.AnyNear(sample_flat[k], [&](int l) {
      if ((l - k) * options.spacing <= options.min_gap) return false;  // also skips l <= k
      const double distance = (sample_flat[l] - sample_flat[k]).norm();
      const double difference = sample_height[k] - sample_height[l];
      if (distance >= options.radius || std::abs(difference) > options.max_difference) return false;
      // Residual h_k + c_k - h_l - c_l with weight w.
      const double w = 1.0 - distance / options.radius;
      normal.emplace_back(k, k, w);
      normal.emplace_back(l, l, w);
      normal.emplace_back(k, l, -w);
      normal.emplace_back(l, k, -w);
      rhs[k] -= w * difference;
      rhs[l] += w * difference;
      ++pairs;
      return false;
    });
  }
  if (pairs == 0) return corrections;
  // Smoothness: second differences c_{k-1} - 2 c_k + c_{k+1}; a small pull to 0 fixes the
  // offset and tilt the pairs and second differences leave free.
  const double coefficients[3] = {1.0, -2.0, 1.0};
  for (int k = 1; k + 1 < n; ++k)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        normal.emplace_back(k - 1 + a, k - 1 + b, options.smoothness * coefficients[a] * coefficients[b]);
  for (int k = 0; k < n; ++k) normal.emplace_back(k, k, kAltitudeAnchorWeight);
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(normal.begin(), normal.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
  Require(solver.info() == Eigen::Success, "altitude reconciliation: the normal equations could not be factorised");
  const Eigen::VectorXd c = solver.solve(rhs);
  Require(solver.info() == Eigen::Success && c.allFinite(), "altitude reconciliation: no solution");
  // Slopes at the samples (central differences, one-sided at the ends), then both to the poses.
  Eigen::VectorXd slope(n);
  for (int k = 0; k < n; ++k) {
    const int a = std::max(k - 1, 0), b = std::min(k + 1, n - 1);
    slope[k] = (c[b] - c[a]) / ((b - a) * options.spacing);
  }
  for (int i = 0; i < num_poses; ++i) {
    const double x = pose_s[i] / options.spacing;
    const int k = std::clamp(static_cast<int>(std::floor(x)), 0, n - 2);
    const double t = std::clamp(x - k, 0.0, 1.0);
    corrections[i].offset = c[k] + t * (c[k + 1] - c[k]);
    corrections[i].slope = slope[k] + t * (slope[k + 1] - slope[k]);
  }
  return corrections;
}

void ApplyAltitudeCorrections(const std::vector<AltitudeCorrection>& corrections,
                              std::vector<Eigen::Isometry3d>* poses) {
  Require(corrections.size() == poses->size(), "altitude corrections: one per pose needed");
  if (poses->empty()) return;
  const Eigen::Vector3d down = TrajectoryDown(*poses);
  const int n = static_cast<int>(poses->size());
  auto horizontal = [&](const Eigen::Vector3d& v) { return Eigen::Vector3d(v - v.dot(down) * down); };
  // Directions of travel (the slope is along the path, whichever way the camera looks), from the
  // original positions.
  std::vector<Eigen::Vector3d> travel(n);
  for (int i = 0; i < n; ++i) {
    travel[i] = horizontal((*poses)[std::min(i + 1, n - 1)].translation() - (*poses)[std::max(i - 1, 0)].translation());
    if (travel[i].norm() < kStandingStillDistance) travel[i] = horizontal((*poses)[i].linear().col(2));
  }
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d& T = (*poses)[i];
    T.translation() += corrections[i].offset * down;
    // Rotating the direction of travel about travel x down by +angle turns it towards down.
    if (travel[i].norm() < kStandingStillDistance || corrections[i].slope == 0) continue;  // standing, looking down
    const Eigen::Vector3d axis = travel[i].normalized().cross(down).normalized();
    T.linear() = Eigen::AngleAxisd(std::atan(corrections[i].slope), axis).toRotationMatrix() * T.linear();
  }
}

std::vector<Eigen::Isometry3d> GenerateDrivingPath(int num_poses, double speed, double frame_interval,
                                                   uint64_t seed) {
  Require(num_poses > 0, "the generated path needs at least one pose");
  Require(speed > 0 && speed < 60, "generated path speed must be in (0, 60) m/s");
  std::mt19937_64 rng(seed * 7919u + 17u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  const double kPi = 3.14159265358979323846;
  // Curvature program: straights and turns, curvature ramped over 6 m.
  double heading = 0, curvature = 0, target = 0, segment_left = 30 + 60 * u(rng);
  bool turning = false;
  Eigen::Vector3d pos = Eigen::Vector3d::Zero();  // x right, y down, z forward
  const double hill_a1 = 1.0 + 1.5 * u(rng), hill_l1 = 180 + 200 * u(rng), hill_p1 = 2 * kPi * u(rng);
  const double hill_a2 = 0.3 + 0.6 * u(rng), hill_l2 = 60 + 80 * u(rng), hill_p2 = 2 * kPi * u(rng);
  auto hill = [&](double s) {
    return hill_a1 * std::sin(2 * kPi * s / hill_l1 + hill_p1) + hill_a2 * std::sin(2 * kPi * s / hill_l2 + hill_p2);
  };
  const double h0 = hill(0);
  Eigen::Vector3d shake = Eigen::Vector3d::Zero();  // slow roll/pitch vibration (rad)
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(num_poses);
  double s = 0, v = speed;
  for (int i = 0; i < num_poses; ++i) {
    const double ds = 0.05;  // integrate in small steps for a smooth path
    const double slope = (hill(s + 0.5) - hill(s - 0.5));
    Eigen::Vector3d forward(std::sin(heading), -slope, std::cos(heading));  // uphill = -y
    forward.normalize();
    const Eigen::Vector3d down_world(0, 1, 0);
    const Eigen::Vector3d x_axis = down_world.cross(forward).normalized();
    const Eigen::Vector3d y_axis = forward.cross(x_axis);
    Eigen::Matrix3d R;
    R.col(0) = x_axis;
    R.col(1) = y_axis;
    R.col(2) = forward;
    shake = 0.9 * shake + 0.0015 * Eigen::Vector3d(gauss(rng), 0.3 * gauss(rng), gauss(rng));
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R * ExpSO3(shake);
    T.translation() = Eigen::Vector3d(pos.x(), -(hill(s) - h0), pos.z());
    poses.push_back(T);
    // Advance one frame.
    v = std::clamp(v + 0.05 * gauss(rng) - 0.02 * (v - speed), 0.5 * speed, 1.3 * speed);
    const double step = v * frame_interval * (turning ? 0.8 : 1.0);
    for (double done = 0; done < step; done += ds) {
      const double d = std::min(ds, step - done);
      curvature += (target - curvature) * std::min(1.0, d / 3.0);  // ~3 m transition
      heading += curvature * d;
      pos.x() += std::sin(heading) * d;
      pos.z() += std::cos(heading) * d;
      s += d;
      segment_left -= d;
      if (segment_left <= 0) {
        turning = !turning;
        if (turning) {
          const double radius = 15 + 45 * u(rng);
          const double angle = (15 + 75 * u(rng)) * kPi / 180;
          target = (u(rng) < 0.5 ? -1 : 1) / radius;
          segment_left = angle * radius;
        } else {
          target = 0;
          segment_left = 40 + 120 * u(rng);
        }
      }
    }
  }
  const Eigen::Isometry3d first_inv = poses.front().inverse();
  for (auto& T : poses) T = first_inv * T;
  return poses;
}

}  // namespace dvso::sim
