#include "vo/frontend/coarse_tracker.h"
#include "vo/optimization/photometric_kernel.h"

#include <Eigen/Cholesky>
#include <cmath>

#include "core/error.h"
#include "core/lie.h"

namespace dvso::vo {

void CoarseTrackerOptions::Check() const {
  Require(huber_threshold > 0, "tracker huber_threshold must be > 0");
  Require(cutoff_threshold >= huber_threshold, "tracker cutoff_threshold must be >= huber_threshold");
  Require(gradient_weight_c > 0, "tracker gradient_weight_c must be > 0");
  Require(max_iterations_finest >= 1 && max_iterations_coarse >= 1, "tracker iterations must be >= 1");
  Require(initial_lambda > 0, "tracker initial_lambda must be > 0");
  Require(convergence_eps > 0, "tracker convergence_eps must be > 0");
  Require(max_affine_a > 0, "tracker max_affine_a must be > 0");
  Require(min_inlier_fraction >= 0 && min_inlier_fraction <= 1, "tracker min_inlier_fraction must be in [0, 1]");
  Require(min_points >= 1, "tracker min_points must be >= 1");
  Require(retrack_ratio >= 1, "tracker retrack_ratio must be >= 1");
}

PointFlow ComputePointFlow(const Eigen::Vector3f& q_full, const Eigen::Vector3f& t, const Eigen::Vector3f& ray,
                           float idepth, float fx, float fy) {
  PointFlow flow;
  // Both projections are of the point scaled by idepth: q = idepth * (R X + t).
  const Eigen::Vector3f q_translation = ray + t * idepth;
  const auto squared_shift = [&](const Eigen::Vector3f& q) {
    const float du = fx * (q.x() / q.z() - ray.x()), dv = fy * (q.y() / q.z() - ray.y());
    return du * du + dv * dv;
  };
  if (q_full.z() > kMinProjectedDepth) {
    flow.has_full = true;
    flow.sq_full = squared_shift(q_full);
  }
  if (q_translation.z() > kMinProjectedDepth) {
    flow.has_translation = true;
    flow.sq_translation = squared_shift(q_translation);
  }
  return flow;
}

CoarseTracker::CoarseTracker(const CoarseTrackerOptions& options) : options_(options) { options_.Check(); }

int CoarseTracker::num_reference_points(int level) const {
  if (level < 0 || level >= static_cast<int>(level_points_.size())) return 0;
  return static_cast<int>(level_points_[level].size());
}

void CoarseTracker::SetReference(ImagePyramidPtr reference, const std::vector<ReferencePoint>& points) {
  Require(reference != nullptr, "CoarseTracker::SetReference: null pyramid");
  reference_ = std::move(reference);
  const int num_levels = reference_->num_levels();
  level_points_.assign(num_levels, {});
  std::vector<float> sum;
  std::vector<float> count;
  for (int l = 0; l < num_levels; ++l) {
    const PyramidLevel& level = reference_->level(l);
    const int w = level.width;
    const int h = level.height;
    sum.assign(static_cast<size_t>(w) * h, 0.f);
    count.assign(static_cast<size_t>(w) * h, 0.f);
    const float scale = 1.0f / static_cast<float>(1 << l);
    for (const ReferencePoint& p : points) {
      if (!(p.idepth > 0) || !std::isfinite(p.idepth)) continue;
      const int x = static_cast<int>(std::lround((p.u + 0.5f) * scale - 0.5f));
      const int y = static_cast<int>(std::lround((p.v + 0.5f) * scale - 0.5f));
      if (x < 0 || y < 0 || x >= w || y >= h) continue;
      sum[static_cast<size_t>(y) * w + x] += p.idepth;
      count[static_cast<size_t>(y) * w + x] += 1.f;
    }
    auto& out = level_points_[l];
    const int border = kTrackerBorder;
    for (int y = border; y < h - border; ++y) {
      for (int x = border; x < w - border; ++x) {
        const size_t i = static_cast<size_t>(y) * w + x;
        if (count[i] <= 0) continue;
        out.push_back({static_cast<float>(x), static_cast<float>(y), sum[i] / count[i], level.data[i][0]});
      }
    }
  }
}

CoarseTracker::LevelStats CoarseTracker::Evaluate(const PyramidLevel& target, int level, const Eigen::Isometry3d& T,
                                                  double a, double b, double cutoff_threshold, Matrix8d* H,
                                                  Vector8d* g) const {
  LevelStats stats;
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const PinholeCamera& cam = target.camera;
  const float fx = static_cast<float>(cam.fx), fy = static_cast<float>(cam.fy);
  const float cx = static_cast<float>(cam.cx), cy = static_cast<float>(cam.cy);
  const float ifx = 1.0f / fx, ify = 1.0f / fy;
  const float ea = static_cast<float>(std::exp(a));
  const float bf = static_cast<float>(b);
  const float huber = static_cast<float>(options_.huber_threshold);
  const float cutoff = static_cast<float>(cutoff_threshold);
  const float c2 = static_cast<float>(options_.gradient_weight_c * options_.gradient_weight_c);
  const bool want_flow = level == 0;
  // Accumulate in float blocks per point and sum into double to keep precision.
  Eigen::Matrix<float, 8, 8> Hf = Eigen::Matrix<float, 8, 8>::Zero();
  Eigen::Matrix<float, 8, 1> gf = Eigen::Matrix<float, 8, 1>::Zero();
  Matrix8d Hd = Matrix8d::Zero();
  Vector8d gd = Vector8d::Zero();
  int block = 0;
  for (const LevelPoint& p : level_points_[level]) {
    const Eigen::Vector3f ray((p.u - cx) * ifx, (p.v - cy) * ify, 1.0f);
    const Eigen::Vector3f q = R * ray + t * p.idepth;  // point scaled by idepth
    if (!(q.z() > kMinProjectedDepth)) continue;
    const float iz = 1.0f / q.z();
    const float un = q.x() * iz, vn = q.y() * iz;
    const float u = fx * un + cx, v = fy * vn + cy;
    if (!target.InBounds(u, v, 1.5f)) continue;
    const Eigen::Vector3f hit = target.Interpolate(u, v);
    const float r = hit[0] - ea * p.intensity - bf;
    const float gx = hit[1], gy = hit[2];
    const float wg = GradientWeight(c2, gx, gy);
    const float ar = std::fabs(r);
    ++stats.num;
    if (want_flow) {
      // q.z() > kMinProjectedDepth was checked above, so the full flow exists.
      const PointFlow flow = ComputePointFlow(q, t, ray, p.idepth, fx, fy);
      stats.flow_sq_rt += flow.sq_full;
      if (flow.has_translation) {
        stats.flow_sq_t += flow.sq_translation;
        ++stats.num_flow_t;
      }
    }
    if (ar > cutoff) {
      stats.energy += wg * huber * (2 * cutoff - huber);
      continue;
    }
    ++stats.num_inliers;
    float hw, rho;
    HuberWeightAndEnergy(r, huber, &hw, &rho);
    stats.energy += wg * rho;
    if (H == nullptr) continue;
    // Inverse depth of the point in the new camera: idepth_new = idepth * iz.
    const Eigen::Matrix<float, 8, 1> J = PoseAffineJacobian(gx * fx, gy * fy, un, vn, p.idepth * iz, ea, p.intensity);
    const float w = hw * wg;
    Hf.noalias() += (w * J) * J.transpose();
    gf.noalias() += (w * r) * J;
    if (++block == 256) {
      Hd += Hf.cast<double>();
      gd += gf.cast<double>();
      Hf.setZero();
      gf.setZero();
      block = 0;
    }
  }
  if (H != nullptr) {
    *H = Hd + Hf.cast<double>();
    *g = gd + gf.cast<double>();
  }
  return stats;
}

TrackingResult CoarseTracker::Track(const ImagePyramid& frame, const Eigen::Isometry3d& T_new_ref_guess,
                                    double a_guess, double b_guess, int max_level) const {
  Require(reference_ != nullptr, "CoarseTracker::Track called without a reference");
  TrackingResult result;
  result.hypotheses_tried = 1;
  Eigen::Isometry3d T = Orthonormalized(T_new_ref_guess);
  double a = a_guess, b = b_guess;
  const int levels = std::min(frame.num_levels(), static_cast<int>(level_points_.size()));
  int top = levels - 1;
  if (max_level >= 0) top = std::min(top, max_level);
  LevelStats stats;
  for (int l = top; l >= 0; --l) {
    const PyramidLevel& target = frame.level(l);
    Matrix8d H;
    Vector8d g;
    // DSO: when most residuals exceed the cutoff (large initial brightness or
    // motion error) the cutoff is raised so that the system still sees them.
    double cutoff = options_.cutoff_threshold;
    stats = Evaluate(target, l, T, a, b, cutoff, &H, &g);
    for (int repeat = 0; repeat < 6 && stats.num >= 8 && stats.num_inliers < 0.4 * stats.num; ++repeat) {
      cutoff *= 2;
      stats = Evaluate(target, l, T, a, b, cutoff, &H, &g);
    }
    if (stats.num < 8) continue;  // too few points at this (coarse) level: go finer
    double lambda = options_.initial_lambda;
    const int iterations = l == 0 ? options_.max_iterations_finest : options_.max_iterations_coarse;
    for (int it = 0; it < iterations; ++it) {
      Matrix8d Hl = H;
      for (int k = 0; k < 8; ++k) Hl(k, k) *= (1.0 + lambda);
      Hl.diagonal().array() += 1e-9;
      if (!options_.estimate_affine) {
        Hl.block<2, 8>(6, 0).setZero();
        Hl.block<8, 2>(0, 6).setZero();
        Hl(6, 6) = Hl(7, 7) = 1.0;
      }
      Vector8d gl = g;
      if (!options_.estimate_affine) gl.tail<2>().setZero();
      const Vector8d delta = -Hl.ldlt().solve(gl);
      if (!delta.allFinite()) break;
      Eigen::Isometry3d T_try = Orthonormalized(ExpSE3(delta.head<6>()) * T);
      const double a_try = a + delta[6];
      const double b_try = b + delta[7];
      Matrix8d H_try;
      Vector8d g_try;
      const LevelStats s_try = Evaluate(target, l, T_try, a_try, b_try, cutoff, &H_try, &g_try);
      // Compare energies per residual (points may leave the image).
      const bool better = s_try.num >= 8 && s_try.energy / s_try.num < stats.energy / std::max(stats.num, 1);
      if (better) {
        T = T_try;
        a = a_try;
        b = b_try;
        H = H_try;
        g = g_try;
        stats = s_try;
        lambda = std::max(lambda * 0.5, 1e-6);
      } else {
        lambda *= 4.0;
        if (lambda > 1e4) break;
      }
      if (delta.norm() < options_.convergence_eps) break;
    }
    if (l == 0 && cutoff != options_.cutoff_threshold) {
      // Report the final quality with the nominal cutoff.
      stats = Evaluate(target, l, T, a, b, options_.cutoff_threshold, nullptr, nullptr);
    }
  }
  result.T_new_ref = T;
  result.affine_a = a;
  result.affine_b = b;
  result.num_residuals = stats.num;
  if (stats.num > 0) {
    result.rmse = std::sqrt(stats.energy / stats.num);
    result.inlier_fraction = static_cast<double>(stats.num_inliers) / stats.num;
    // Mean over the points that have a translation-only flow (ComputePointFlow); none: no shift.
    result.flow_sq_t = stats.num_flow_t > 0 ? stats.flow_sq_t / stats.num_flow_t : 0.0;
    result.flow_sq_rt = stats.flow_sq_rt / stats.num;
  }
  result.success = stats.num >= options_.min_points && result.inlier_fraction >= options_.min_inlier_fraction &&
                   std::fabs(a) <= options_.max_affine_a && T.matrix().allFinite() && std::isfinite(result.rmse);
  return result;
}

TrackingResult CoarseTracker::TrackWithHypotheses(const ImagePyramid& frame,
                                                  const std::vector<Eigen::Isometry3d>& guesses, double a_guess,
                                                  double b_guess, double reference_rmse) const {
  TrackingResult best;
  int tried = 0;
  for (const Eigen::Isometry3d& guess : guesses) {
    TrackingResult r = Track(frame, guess, a_guess, b_guess);
    ++tried;
    const bool better = r.success && (!best.success || r.rmse < best.rmse);
    if (better) best = r;
    // Without a reference rmse (first frame of a map) every hypothesis is tried.
    if (best.success && reference_rmse > 0 && best.rmse < options_.retrack_ratio * reference_rmse) break;
  }
  best.hypotheses_tried = tried;
  return best;
}

std::vector<Eigen::Isometry3d> CoarseTracker::MotionHypotheses(const Eigen::Isometry3d& T_last_ref,
                                                               const Eigen::Isometry3d& velocity) {
  std::vector<Eigen::Isometry3d> out;
  const Vector6d log_v = LogSE3(velocity);
  out.push_back(velocity * T_last_ref);                   // constant velocity
  out.push_back(velocity * velocity * T_last_ref);        // double motion (a frame was skipped)
  out.push_back(ExpSE3(0.5 * log_v) * T_last_ref);        // half motion
  out.push_back(T_last_ref);                              // no motion
  const double delta = 0.02;                               // rad, DSO rotDelta
  for (int axis = 0; axis < 3; ++axis) {
    for (double sign : {1.0, -1.0}) {
      Vector6d xi = Vector6d::Zero();
      xi[3 + axis] = sign * delta;
      out.push_back(ExpSE3(xi) * velocity * T_last_ref);
    }
  }
  return out;
}

}  // namespace dvso::vo
