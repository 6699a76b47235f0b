// Marginalisation of a keyframe (DSO): its points go into the prior through
// the Schur complement on their inverse depths, then the keyframe's own
// parameters are Schur-complemented out of the prior. Points the newest
// keyframe no longer observes leave earlier, on their own (DSO
// flagPointsForRemoval), the same way.
//
// Simplifications w.r.t. DSO (the options are in window.h):
//  - a hosted point is marginalised when it still has at least
//    options.min_residuals_to_marginalize active temporal residuals,
//    otherwise dropped (it carries no information on the remaining frames);
//  - residuals of points hosted elsewhere that target the leaving keyframe are
//    dropped (as DSO does), not marginalised; points left without residuals
//    are removed.
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "vo/optimization/accumulator.h"
#include "vo/optimization/marginalization.h"
#include "vo/optimization/window.h"

namespace dvso::vo {

MarginalizedPoint Window::DescribeLeavingPoint(int host_index, int point_index) const {
  const Keyframe& host = keyframes_[host_index];
  const Point& p = host.points[point_index];
  MarginalizedPoint out;
  out.stereo_energy = StaticStereoEnergy(p);
  int active = 0;
  for (const Residual& r : p.residuals) {
    if (r.state != ResidualState::kActive) continue;
    out.num_residuals += r.kind == ResidualKind::kTemporal;
    ++active;
    out.mean_energy += r.energy;
  }
  if (active > 0) out.mean_energy /= active;
  out.idepth_hessian = p.idepth_hessian;
  out.idepth_hessian_temporal = p.idepth_hessian_temporal;
  out.host_id = host.id;
  out.u = p.u;
  out.v = p.v;
  out.idepth = p.idepth;
  const Eigen::Vector3d ray = camera_.left.Unproject(p.u, p.v);
  out.world = host.world_to_camera.inverse() * (ray / std::max(p.idepth, options_.min_idepth));
  return out;
}

void Window::MarginalizePointsIntoPrior(const std::vector<PointRef>& points) {
  if (points.empty()) return;
  // Their information on the frames, depths eliminated (Schur), linearised
  // at the current state, re-expanded around the first estimates.
  WindowLinearizer linearizer(&keyframes_, camera_, options_);
  linearizer.Linearize(points);
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  linearizer.Reduce(0.0, Eigen::MatrixXd(), Eigen::VectorXd(), &H, &b);
  AddToPrior(H, b, FirstEstimateDifference(keyframes_), &prior_H_, &prior_b_);
  ProjectPriorToPositiveSemidefinite(&prior_H_, &prior_b_);
}

std::vector<MarginalizedPoint> Window::MarginalizeInvisiblePoints() {
  std::vector<MarginalizedPoint> leaving;
  const int n = num_keyframes();
  if (n < 2) return leaving;
  const int newest_id = keyframes_[n - 1].id;
  const int previous_id = keyframes_[n - 2].id;
  // Residual states at the current estimate (Optimize() leaves them current).
  if (!residual_states_current_) EvaluateWindowEnergy(&keyframes_, camera_, options_, true);
  SyncFreeLinearizationPoints(&keyframes_);
  std::vector<PointRef> informative;
  std::vector<std::vector<uint8_t>> leaves(keyframes_.size());
  for (int h = 0; h + 1 < n; ++h) {
    const Keyframe& host = keyframes_[h];
    leaves[h].assign(host.points.size(), 0);
    for (int i = 0; i < static_cast<int>(host.points.size()); ++i) {
      const Point& p = host.points[i];
      const Residual* to_newest = nullptr;
      const Residual* to_previous = nullptr;
      for (const Residual& r : p.residuals) {
        if (r.kind != ResidualKind::kTemporal) continue;
        if (r.target_id == newest_id) to_newest = &r;
        if (r.target_id == previous_id) to_previous = &r;
      }
      // DSO PointHessian::isOOB: out of the newest image, or an outlier in both
      // of the two newest keyframes (a residual into the previous one that is
      // gone was removed as an outlier; a point hosted there has none).
      const bool out_of_newest = to_newest == nullptr || to_newest->state == ResidualState::kOutOfBounds;
      const bool outlier_twice = to_newest != nullptr && to_newest->state == ResidualState::kOutlier &&
                                 h != n - 2 && (to_previous == nullptr || to_previous->state != ResidualState::kActive);
      if (!out_of_newest && !outlier_twice) continue;
      leaves[h][i] = 1;
      leaving.push_back(DescribeLeavingPoint(h, i));
      if (leaving.back().num_residuals >= options_.min_residuals_to_marginalize) informative.push_back({h, i});
    }
  }
  if (leaving.empty()) return leaving;
  MarginalizePointsIntoPrior(informative);
  FixConnectedLinearizationPoints(prior_H_, &keyframes_);
  for (int h = 0; h + 1 < num_keyframes(); ++h) {
    std::vector<Point>& points = keyframes_[h].points;
    size_t k = 0;
    for (size_t i = 0; i < points.size(); ++i) {
      if (leaves[h][i]) continue;
      if (k != i) points[k] = std::move(points[i]);  // no self-move: it would empty the residuals
      ++k;
    }
    points.resize(k);
  }
  return leaving;
}

std::vector<MarginalizedPoint> Window::MarginalizeKeyframe(int id) {
  int index = -1;
  for (int i = 0; i < num_keyframes(); ++i) {
    if (keyframes_[i].id == id) index = i;
  }
  Require(index >= 0, "window: MarginalizeKeyframe: no keyframe with id " + std::to_string(id));

  residual_states_current_ = false;
  // Keyframes not yet in the prior are linearised at their current estimate.
  SyncFreeLinearizationPoints(&keyframes_);

  // 1. States of the hosted points' residuals at the current estimate.
  std::vector<PointRef> hosted = CollectPoints(keyframes_, index);
  std::vector<MarginalizedPoint> leaving;
  if (!hosted.empty()) {
    WindowLinearizer probe(&keyframes_, camera_, options_);
    probe.Linearize(hosted);
    std::vector<PointRef> informative;
    for (const PointRef& ref : hosted) {
      leaving.push_back(DescribeLeavingPoint(index, ref.point_index));
      if (leaving.back().num_residuals >= options_.min_residuals_to_marginalize) informative.push_back(ref);
    }
    // 2. Their information on the frames goes into the prior.
    MarginalizePointsIntoPrior(informative);
  }

  // 3. The leaving keyframe's own absolute priors (gauge, affine) join the prior.
  {
    Matrix8d H_abs;
    Vector8d b_abs;
    double unused = 0.0;
    AbsoluteFramePrior(keyframes_[index], &H_abs, &b_abs, &unused);
    const Eigen::VectorXd dx = FirstEstimateDifference(keyframes_);
    const int o = kFrameParams * index;
    prior_H_.block<8, 8>(o, o) += H_abs;
    prior_b_.segment<8>(o) += b_abs - H_abs * dx.segment<8>(o);
  }

  // 4. Schur complement of the keyframe's parameters out of the prior.
  MarginalizeBlock(kFrameParams * index, kFrameParams, &prior_H_, &prior_b_);
  ProjectPriorToPositiveSemidefinite(&prior_H_, &prior_b_);

  // 5. Drop the keyframe, its points, and all residuals into it; keyframes
  //    that now carry prior information keep their linearisation point.
  keyframes_.erase(keyframes_.begin() + index);
  FixConnectedLinearizationPoints(prior_H_, &keyframes_);
  for (Keyframe& kf : keyframes_) {
    for (Point& p : kf.points) {
      p.residuals.erase(std::remove_if(p.residuals.begin(), p.residuals.end(),
                                       [id](const Residual& r) {
                                         return r.kind == ResidualKind::kTemporal && r.target_id == id;
                                       }),
                        p.residuals.end());
    }
    kf.points.erase(std::remove_if(kf.points.begin(), kf.points.end(),
                                   [](const Point& p) { return p.residuals.empty(); }),
                    kf.points.end());
  }
  return leaving;
}

double MarginalizationDistanceScore(const std::vector<Eigen::Isometry3d>& world_to_camera,
                                    const std::vector<bool>& leaving, int i) {
  constexpr double kDistanceEps = 1e-5;  // m: keeps coincident keyframes finite
  const int n = static_cast<int>(world_to_camera.size());
  Require(i >= 0 && i + 1 < n && static_cast<int>(leaving.size()) == n,
          "MarginalizationDistanceScore: keyframe index out of range");
  // |translation of T_i T_j^-1| = |R_i (c_j - c_i)| = distance between the camera centres.
  const auto distance = [&](int j) { return (world_to_camera[i] * world_to_camera[j].inverse()).translation().norm(); };
  double sum = 0.0;
  for (int j = 0; j + 1 < n; ++j) {
    if (j == i || leaving[j]) continue;
    sum += 1.0 / (distance(j) + kDistanceEps);
  }
  return std::sqrt(distance(n - 1) + kDistanceEps) * sum;
}

std::vector<int> Window::KeyframesToMarginalize() const {
  std::vector<int> result;
  const int n = num_keyframes();
  if (n < 2) return result;
  std::vector<bool> flagged(n, false);
  int remaining = n;
  // Keyframes that lost almost all their points (DSO: < 5 % left), or whose
  // brightness drifted too far from the newest's (DSO setting_maxLogAffFacInWindow).
  const double newest_a = keyframes_.back().a;
  for (int i = 0; i + 1 < n && remaining > options_.min_keyframes_kept; ++i) {
    const Keyframe& kf = keyframes_[i];
    if ((kf.num_points_added > 0 && kf.points.size() < 0.05 * kf.num_points_added) ||
        std::abs(kf.a - newest_a) > options_.max_log_affine_in_window) {
      flagged[i] = true;
      --remaining;
    }
  }
  // Distance heuristic (DSO), MarginalizationDistanceScore: the largest score leaves first.
  std::vector<Eigen::Isometry3d> poses;
  if (remaining > options_.max_keyframes - 1) {
    poses.reserve(n);
    for (const Keyframe& kf : keyframes_) poses.push_back(kf.world_to_camera);
  }
  while (remaining > options_.max_keyframes - 1) {
    int best = -1;
    double best_score = -1.0;
    for (int i = 0; i + 1 < n; ++i) {
      if (flagged[i]) continue;
      const double score = MarginalizationDistanceScore(poses, flagged, i);
      if (score > best_score) {
        best_score = score;
        best = i;
      }
    }
    if (best < 0) break;
    flagged[best] = true;
    --remaining;
  }
  for (int i = 0; i < n; ++i) {
    if (flagged[i]) result.push_back(keyframes_[i].id);
  }
  return result;
}

}  // namespace dvso::vo
