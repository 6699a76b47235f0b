#include "vo/optimization/residuals.h"

#include <cmath>

namespace dvso::vo {
namespace {

void SetIntrinsics(const PinholeCamera& camera, ResidualGeometry* g) {
  g->fx = static_cast<float>(camera.fx);
  g->fy = static_cast<float>(camera.fy);
  g->cx = static_cast<float>(camera.cx);
  g->cy = static_cast<float>(camera.cy);
}

// Bilinear sample of a CV_32F map with its x derivative (of the bilinear
// interpolant). False when outside or a tap that enters is invalid (<= 0, NaN).
// Points sit on integer rows, and the virtual right camera keeps the row: the
// lower row's weight is then 0 and it is not asked for (an invalid pixel below
// a valid one must not remove the residual). Both columns are always needed:
// the derivative is their difference.
bool SampleDisparity(const cv::Mat& map, float x, float y, float* value, float* dx) {
  if (!(x >= 0.0f && y >= 0.0f && x < map.cols - 1 && y < map.rows - 1)) return false;
  const int ix = static_cast<int>(x);
  const int iy = static_cast<int>(y);
  const float fx = x - ix;
  const float fy = y - iy;
  const float* row0 = map.ptr<float>(iy) + ix;
  const float d00 = row0[0], d01 = row0[1];
  if (!(d00 > 0.0f && d01 > 0.0f)) return false;  // also rejects NaN
  if (fy == 0.0f) {
    *value = (1 - fx) * d00 + fx * d01;
    *dx = d01 - d00;
    return true;
  }
  const float* row1 = map.ptr<float>(iy + 1) + ix;
  const float d10 = row1[0], d11 = row1[1];
  if (!(d10 > 0.0f && d11 > 0.0f)) return false;
  *value = (1 - fy) * ((1 - fx) * d00 + fx * d01) + fy * ((1 - fx) * d10 + fx * d11);
  *dx = (1 - fy) * (d01 - d00) + fy * (d11 - d10);
  return true;
}

// A residual is an outlier when its energy per pattern pixel exceeds the threshold (DSO). The test is on
// the energy before the term's coupling weight (mu, lambda): the weights say how much a term counts, not
// how badly a point may match (with the weight inside, lambda = 2 halved the tolerance and a lambda sweep
// measured the gating as well as the coupling).
ResidualState OutlierTest(float weighted_energy, const ResidualGeometry& g, const WindowOptions& options) {
  const float energy = g.term_weight > 0 ? weighted_energy / g.term_weight : weighted_energy;
  return energy > kPatternSize * options.outlier_energy_threshold ? ResidualState::kOutlier : ResidualState::kActive;
}

void EvaluateVirtualStereo(const ResidualGeometry& g, const Point& point, double idepth,
                           const WindowOptions& options, bool with_jacobians, ResidualEvaluation* out) {
  const float gamma = static_cast<float>(options.huber_threshold);
  const float c_sq = static_cast<float>(options.gradient_weight_c * options.gradient_weight_c);
  const float border = static_cast<float>(options.image_border);
  // Rectified virtual right camera at +B_v along x: Pi(Pi^-1(p, d) + t_b) with
  // t_b = (-B_v, 0, 0) shifts every pixel by the disparity fx * B_v * d.
  const float shift = g.fx * g.baseline * static_cast<float>(idepth);
  const float dshift_dd = g.fx * g.baseline;
  float energy = 0.0f;
  for (int k = 0; k < kPatternSize; ++k) {
    const float u = point.u + kPatternOffsets[k][0];
    const float v = point.v + kPatternOffsets[k][1];
    const float u_dagger = u - shift;
    float disparity = 0.0f, ddisp_dx = 0.0f;
    if (!SampleDisparity(*g.disparity, u_dagger, v, &disparity, &ddisp_dx)) {
      out->state = ResidualState::kOutOfBounds;
      return;
    }
    // I_dagger[p_dagger] = I_i[p_dagger + (D^R(p_dagger), 0)].
    const float x_left = u_dagger + disparity;
    if (!g.target->InBounds(x_left, v, border)) {
      out->state = ResidualState::kOutOfBounds;
      return;
    }
    const Eigen::Vector3f sample = g.target->Interpolate(x_left, v);
    const float r = sample[0] - point.host_intensity[k];
    float huber_weight, rho;
    HuberWeightAndEnergy(r, gamma, &huber_weight, &rho);
    const float w_p = g.term_weight * GradientWeight(c_sq, sample[1], sample[2]);
    energy += w_p * rho;
    out->r[k] = r;
    if (with_jacobians) {
      out->weight[k] = w_p * huber_weight;
      // d x_left / d d = (1 + dD^R/dx) * d u_dagger / d d = -(1 + dD^R/dx) fx B_v.
      out->J_idepth[k] = sample[1] * (-(1.0f + ddisp_dx) * dshift_dd);
      out->J_pair.row(k).setZero();
    }
  }
  out->energy = energy;
  out->state = OutlierTest(energy, g, options);
}

}  // namespace

ResidualGeometry TemporalGeometry(const Keyframe& host, const Keyframe& target, const PinholeCamera& camera,
                                  const WindowOptions& options) {
  ResidualGeometry g;
  g.kind = ResidualKind::kTemporal;
  SetIntrinsics(camera, &g);
  const Eigen::Isometry3d T = RelativePose(target.world_to_camera, host.world_to_camera);
  g.R = T.linear().cast<float>();
  g.t = T.translation().cast<float>();
  if (options.first_estimate_jacobians) {
    const Eigen::Isometry3d T0 = RelativePose(target.world_to_camera_fej, host.world_to_camera_fej);
    g.R_fej = T0.linear().cast<float>();
    g.t_fej = T0.translation().cast<float>();
    g.fej_is_current = g.R_fej == g.R && g.t_fej == g.t;
  } else {
    g.R_fej = g.R;
    g.t_fej = g.t;
  }
  g.affine_scale = static_cast<float>(std::exp(target.a - host.a));
  g.b_host = static_cast<float>(host.b);
  g.b_target = static_cast<float>(target.b);
  g.term_weight = ResidualTermWeight(ResidualKind::kTemporal, options);
  g.target = &target.left->level(0);
  g.has_frame_jacobians = true;
  return g;
}

ResidualGeometry StaticStereoGeometry(const Keyframe& host, const StereoCamera& camera,
                                      const WindowOptions& options) {
  ResidualGeometry g;
  g.kind = ResidualKind::kStaticStereo;
  SetIntrinsics(camera.left, &g);
  // Right camera at +B along x: X_right = X_left - (B, 0, 0).
  g.t = Eigen::Vector3f(-static_cast<float>(camera.baseline), 0.0f, 0.0f);
  g.t_fej = g.t;
  // The right image relates to its own left image by the pair's transfer
  // I_right ~ gain (1 + radial rho^2) * I_left + bias (vo/frame/stereo_brightness.h), not by the
  // keyframes' a, b: r = (I_right(p') - bias) - gain (1 + radial rho(p)^2) * I_left(p).
  g.affine_scale = static_cast<float>(host.right_brightness.gain);
  g.radial_gain = static_cast<float>(host.right_brightness.radial);
  g.radial_position = BasicRadialPosition<float>(camera.left);
  g.b_host = 0.0f;
  g.b_target = static_cast<float>(host.right_brightness.bias);
  g.term_weight = ResidualTermWeight(ResidualKind::kStaticStereo, options);
  g.target = &host.right->level(0);
  g.has_frame_jacobians = false;
  return g;
}

ResidualGeometry VirtualStereoGeometry(const Keyframe& host, const PinholeCamera& camera,
                                       const WindowOptions& options) {
  ResidualGeometry g;
  g.kind = ResidualKind::kVirtualStereo;
  SetIntrinsics(camera, &g);
  g.baseline = static_cast<float>(options.virtual_stereo_baseline);
  g.term_weight = ResidualTermWeight(ResidualKind::kVirtualStereo, options);
  g.target = &host.left->level(0);
  g.disparity = &host.right_disparity;
  g.has_frame_jacobians = false;
  return g;
}

void PrefetchResidual(const ResidualGeometry& g, const Point& point, double idepth) {
  float x = point.u, y = point.v;
  const float d = static_cast<float>(idepth);
  if (g.kind == ResidualKind::kVirtualStereo) {
    // D^R is read at the shifted pixel u - fx B_v d; the image read that
    // follows lands back near u (u - shift + D^R ~ u), prefetched below.
    const int dx = static_cast<int>(x - g.fx * g.baseline * d) - kPatternRadius;
    const int dy = static_cast<int>(y) - kPatternRadius;
    const cv::Mat& map = *g.disparity;
    if (dx >= 0 && dy >= 0 && dx + 2 * kPatternRadius + 1 < map.cols && dy + 2 * kPatternRadius + 1 < map.rows) {
      for (int r = 0; r <= 2 * kPatternRadius + 1; ++r) __builtin_prefetch(map.ptr<float>(dy + r) + dx);
    }
  } else {
    const Eigen::Vector3f q = g.R * Eigen::Vector3f((x - g.cx) / g.fx, (y - g.cy) / g.fy, 1.0f) + d * g.t;
    if (!(q.z() > 1e-6f)) return;
    x = g.fx * q.x() / q.z() + g.cx;
    y = g.fy * q.y() / q.z() + g.cy;
  }
  const PyramidLevel& level = *g.target;
  if (!level.InBounds(x, y, kPatternRadius + 2.0f)) return;
  const int ix = static_cast<int>(x) - kPatternRadius;
  const int iy = static_cast<int>(y) - kPatternRadius;
  for (int r = 0; r <= 2 * kPatternRadius + 1; ++r) {
    const Eigen::Vector3f* row = level.data.data() + static_cast<size_t>(iy + r) * level.width + ix;
    __builtin_prefetch(row);
    __builtin_prefetch(row + 2 * kPatternRadius + 1);
  }
}

void EvaluateResidual(const ResidualGeometry& g, const Point& point, double idepth, const WindowOptions& options,
                      bool with_jacobians, ResidualEvaluation* out) {
  if (g.kind == ResidualKind::kVirtualStereo) {
    EvaluateVirtualStereo(g, point, idepth, options, with_jacobians, out);
    return;
  }
  const float gamma = static_cast<float>(options.huber_threshold);
  const float c_sq = static_cast<float>(options.gradient_weight_c * options.gradient_weight_c);
  const float border = static_cast<float>(options.image_border);
  const float d = static_cast<float>(idepth);
  float energy = 0.0f;
  for (int k = 0; k < kPatternSize; ++k) {
    const float u = point.u + kPatternOffsets[k][0];
    const float v = point.v + kPatternOffsets[k][1];
    const Eigen::Vector3f ray((u - g.cx) / g.fx, (v - g.cy) / g.fy, 1.0f);
    // q = R Pi^-1(p, 1) + d t is the target point scaled by d: no division by
    // d, so points at infinity (d -> 0) stay well defined.
    const Eigen::Vector3f q = g.R * ray + d * g.t;
    if (!(q.z() > 1e-6f)) {
      out->state = ResidualState::kOutOfBounds;
      return;
    }
    const float inv_qz = 1.0f / q.z();
    const float un = q.x() * inv_qz;
    const float vn = q.y() * inv_qz;
    const float x = g.fx * un + g.cx;
    const float y = g.fy * vn + g.cy;
    if (!g.target->InBounds(x, y, border)) {
      out->state = ResidualState::kOutOfBounds;
      return;
    }
    const Eigen::Vector3f sample = g.target->Interpolate(x, y);
    const float host_term = point.host_intensity[k] - g.b_host;
    // Radial term of the stereo transfer at the host pattern pixel (constant in every parameter, so
    // no Jacobian changes: static stereo has no frame Jacobians and J_idepth is the target's gradient).
    const float scale = g.radial_gain == 0.0f
                            ? g.affine_scale
                            : g.affine_scale * (1.0f + g.radial_gain * g.radial_position.Sq(u, v));
    const float r = (sample[0] - g.b_target) - scale * host_term;
    float huber_weight, rho;
    HuberWeightAndEnergy(r, gamma, &huber_weight, &rho);
    const float w_p = g.term_weight * GradientWeight(c_sq, sample[1], sample[2]);
    energy += w_p * rho;
    out->r[k] = r;
    if (!with_jacobians) continue;
    out->weight[k] = w_p * huber_weight;
    const float gx = sample[1] * g.fx;  // dI/d(normalised x)
    const float gy = sample[2] * g.fy;
    // Geometric derivatives at the FEJ relative pose (== current one unless
    // the keyframes are in the prior), image gradient at the current p~. The
    // inverse-depth derivative uses the same pose as the pose derivatives so
    // that the scale direction (d t invariant) stays exactly unobservable.
    Eigen::Vector3f q0 = q;
    if (!g.fej_is_current) {
      q0 = g.R_fej * ray + d * g.t_fej;
      if (!(q0.z() > 1e-6f)) q0 = q;  // FEJ pose far off: fall back to the current one
    }
    const float inv_q0z = 1.0f / q0.z();
    const float u0 = q0.x() * inv_q0z;
    const float v0 = q0.y() * inv_q0z;
    // Inverse depth: d un / d d = (t_x - un t_z) / q_z.
    out->J_idepth[k] = (gx * (g.t_fej.x() - u0 * g.t_fej.z()) + gy * (g.t_fej.y() - v0 * g.t_fej.z())) * inv_q0z;
    if (!g.has_frame_jacobians) {
      out->J_pair.row(k).setZero();
      continue;
    }
    // Pose (left twist of the relative pose, photometric_kernel.h) with
    // X = q / d and d_t = d / q_z the inverse depth in the target.
    out->J_pair.row(k).head<6>() = PoseJacobian(gx, gy, u0, v0, d * inv_q0z).transpose();
    // Affine: r = (I_j - b_j) - e^{a_j - a_i} (I_i - b_i).
    out->J_pair(k, 6) = g.affine_scale * host_term;   // d/da_i
    out->J_pair(k, 7) = g.affine_scale;               // d/db_i
    out->J_pair(k, 8) = -g.affine_scale * host_term;  // d/da_j
    out->J_pair(k, 9) = -1.0f;                        // d/db_j
  }
  out->energy = energy;
  out->state = OutlierTest(energy, g, options);
}

}  // namespace dvso::vo
