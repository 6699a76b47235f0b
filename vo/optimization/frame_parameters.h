// Keyframe parameter blocks of the windowed bundle adjustment: 8 per keyframe,
// [xi (6, twist [v; w] of a left-multiplied update of T_cw), a, b]. Helpers for
// the adjoint that maps absolute pose updates to relative ones and for the
// tangent-space difference x [-] x0 used by the priors (FEJ).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/lie.h"

namespace dvso::vo {

constexpr int kFrameParams = 8;  // [xi(6), a, b]
using Vector8d = Eigen::Matrix<double, kFrameParams, 1>;
using Matrix8d = Eigen::Matrix<double, kFrameParams, kFrameParams>;

// Adjoint of T = [R t] for twists [v; w]: Exp(Adj(T) xi) = T Exp(xi) T^-1.
inline Matrix6d Adjoint(const Eigen::Isometry3d& T) {
  Matrix6d adj = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.linear();
  adj.topLeftCorner<3, 3>() = R;
  adj.topRightCorner<3, 3>() = Skew(T.translation()) * R;
  adj.bottomRightCorner<3, 3>() = R;
  return adj;
}

// Relative pose target <- host from absolute world-to-camera poses. With
// left-multiplied updates T_h <- Exp(xi_h) T_h, T_t <- Exp(xi_t) T_t the
// relative pose changes (to first order) by the left twist
//   xi_rel = xi_t - Adj(T_th) xi_h,
// which is how host/target Jacobians are obtained from relative ones.
inline Eigen::Isometry3d RelativePose(const Eigen::Isometry3d& target_world_to_camera,
                                      const Eigen::Isometry3d& host_world_to_camera) {
  return target_world_to_camera * host_world_to_camera.inverse();
}

// Left tangent difference of poses: Log(T * T0^-1), the twist that moves T0 to T.
inline Vector6d PoseDifference(const Eigen::Isometry3d& T, const Eigen::Isometry3d& T0) {
  return LogSE3(T * T0.inverse());
}

// Applies an 8-vector update to a keyframe's (pose, a, b).
inline void ApplyFrameUpdate(const Vector8d& delta, Eigen::Isometry3d* world_to_camera, double* a, double* b) {
  *world_to_camera = ExpSE3(delta.head<6>()) * (*world_to_camera);
  // Re-orthonormalise to keep rounding from accumulating over many updates.
  const Eigen::Quaterniond q(world_to_camera->linear());
  world_to_camera->linear() = q.normalized().toRotationMatrix();
  *a += delta(6);
  *b += delta(7);
}

}  // namespace dvso::vo
