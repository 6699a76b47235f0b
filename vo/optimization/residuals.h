// The residual kinds of the window energy, all with one shape: per pattern
// pixel a residual r, an IRLS weight (gradient weight x Huber weight x term
// weight) and analytic Jacobians w.r.t. the "pair parameters"
//   y = [xi_rel (6), a_host, b_host, a_target, b_target]
// and the point's inverse depth d. The accumulator maps y to the absolute
// host/target parameters with the adjoint and never looks at the kind.
//
//  - temporal (eq. 5.1):      r = (I_j[p~] - b_j) - e^{a_j - a_i} (I_i[p] - b_i),
//                             p~ = Pi(R Pi^-1(p, d) + t), (R, t) = T_ji.
//  - static stereo (Stereo DSO): the same with I_j the host's right image,
//                             (R, t) = (I, (-B, 0, 0)) fixed, the right image
//                             sharing the host's a, b: only dr/dd is non-zero.
//  - virtual stereo (eq. 5.8): p_dagger = Pi(Pi^-1(p, d) + t_b), t_b = (-B_v, 0, 0),
//                             r = I_i[p_dagger + (D^R(p_dagger), 0)] - I_i[p]
//                             (KITTI sign of D^R), only dr/dd, weighted by lambda.
//
// Gradient-dependent weight (DSO): w_p = c^2 / (c^2 + |grad I|^2) at the
// sampled position, treated as a constant in the Jacobians. Huber norm with
// threshold gamma: energy rho(r) = r^2 (|r| <= gamma), 2 gamma |r| - gamma^2 else.
#pragma once

#include <Eigen/Core>

#include "vo/optimization/frame_parameters.h"
#include "vo/frame/stereo_brightness.h"
#include "vo/optimization/photometric_kernel.h"
#include "vo/optimization/window.h"

namespace dvso::vo {

constexpr int kPairParams = 10;  // [xi_rel(6), a_i, b_i, a_j, b_j]

// Everything a residual needs about its (host, target) pair, computed once per
// pair and linearisation.
struct ResidualGeometry {
  ResidualKind kind = ResidualKind::kTemporal;
  // Current relative pose target <- host (for the residual value and dr/dd).
  Eigen::Matrix3f R = Eigen::Matrix3f::Identity();
  Eigen::Vector3f t = Eigen::Vector3f::Zero();
  // Relative pose at the first estimates (FEJ) for the pose Jacobians.
  Eigen::Matrix3f R_fej = Eigen::Matrix3f::Identity();
  Eigen::Vector3f t_fej = Eigen::Vector3f::Zero();
  bool fej_is_current = true;  // (R_fej, t_fej) == (R, t): the second projection is skipped
  float affine_scale = 1.0f;  // e^{a_j - a_i}; static stereo: the transfer's gain
  // Static stereo only: the transfer's radial term, scale = affine_scale (1 + radial_gain rho^2) at the
  // host pixel (StereoBrightness); 0 elsewhere.
  float radial_gain = 0.0f;
  BasicRadialPosition<float> radial_position;  // rho^2 of a host pixel
  float b_host = 0.0f, b_target = 0.0f;
  float term_weight = 1.0f;   // 1 (temporal), mu (static stereo), lambda (virtual stereo)
  float fx = 0, fy = 0, cx = 0, cy = 0;  // level-0 intrinsics
  float baseline = 0.0f;      // virtual stereo: B_v (metres)
  const PyramidLevel* target = nullptr;  // image sampled at p~ (host level 0 for virtual stereo)
  const cv::Mat* disparity = nullptr;    // virtual stereo: D^R (CV_32F, host size)
  bool has_frame_jacobians = true;       // false for the two stereo kinds
};

struct ResidualEvaluation {
  ResidualState state = ResidualState::kActive;
  float energy = 0.0f;  // sum over pattern pixels of term_weight * w_p * rho(r)
  Eigen::Matrix<float, kPatternSize, 1> r = Eigen::Matrix<float, kPatternSize, 1>::Zero();
  Eigen::Matrix<float, kPatternSize, 1> weight = Eigen::Matrix<float, kPatternSize, 1>::Zero();  // IRLS weight
  Eigen::Matrix<float, kPatternSize, kPairParams> J_pair =
      Eigen::Matrix<float, kPatternSize, kPairParams>::Zero();  // dr/dy
  Eigen::Matrix<float, kPatternSize, 1> J_idepth = Eigen::Matrix<float, kPatternSize, 1>::Zero();  // dr/dd
};

// Geometry of a temporal residual host -> target (first_estimate_jacobians
// selects FEJ relative pose for the pose Jacobians).
ResidualGeometry TemporalGeometry(const Keyframe& host, const Keyframe& target, const PinholeCamera& camera,
                                  const WindowOptions& options);
// Geometry of the static stereo residual of `host` (needs host.right).
ResidualGeometry StaticStereoGeometry(const Keyframe& host, const StereoCamera& camera,
                                      const WindowOptions& options);
// Geometry of the virtual stereo residual of `host` (needs host.right_disparity).
ResidualGeometry VirtualStereoGeometry(const Keyframe& host, const PinholeCamera& camera,
                                       const WindowOptions& options);

// Evaluates one residual (all pattern pixels) of `point` for the given
// geometry. With `with_jacobians` false only state, r and energy are filled.
// A residual is kOutOfBounds if any pattern pixel leaves the image (or the
// point is behind the target camera), kOutlier if its energy exceeds
// kPatternSize * outlier_energy_threshold.
void EvaluateResidual(const ResidualGeometry& geometry, const Point& point, double idepth,
                      const WindowOptions& options, bool with_jacobians, ResidualEvaluation* out);

// Hints the cache about the target-image rows the residual of `point` will
// read (its projected pattern), so that the next residual's image reads
// overlap with the current one's arithmetic. No effect on results.
void PrefetchResidual(const ResidualGeometry& geometry, const Point& point, double idepth);

// The coupling weight of a residual kind in the total energy: 1 (temporal), mu (static stereo), lambda
// (virtual stereo).
inline float ResidualTermWeight(ResidualKind kind, const WindowOptions& options) {
  switch (kind) {
    case ResidualKind::kStaticStereo:
      return static_cast<float>(options.static_stereo_weight);
    case ResidualKind::kVirtualStereo:
      return static_cast<float>(options.virtual_stereo_weight);
    case ResidualKind::kTemporal:
      break;
  }
  return 1.0f;
}

// Energy that an out-of-bounds/outlier residual of `kind` counts with when comparing energies across an LM
// step (so that leaving the image is not "free"): the outlier threshold's energy at the term's weight, the
// largest weighted energy an active residual of that kind can have (the outlier test is before the weight).
inline float CappedResidualEnergy(const WindowOptions& options, ResidualKind kind) {
  return static_cast<float>(kPatternSize * options.outlier_energy_threshold) * ResidualTermWeight(kind, options);
}

}  // namespace dvso::vo
