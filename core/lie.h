// Minimal Lie-group helpers on Eigen types (SO(3), SE(3)). Twists are ordered
// [v; w] (translation part first, rotation part second), left-multiplied:
// T_new = Exp(xi) * T.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace dvso {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

inline Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  if (theta < 1e-10) return Eigen::Matrix3d::Identity() + Skew(w);
  return Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
}

// Rotation angle in radians, robust near 0 and pi.
inline double RotationAngle(const Eigen::Matrix3d& R) {
  const double c = std::max(-1.0, std::min(1.0, 0.5 * (R.trace() - 1.0)));
  return std::acos(c);
}

inline Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

// Left Jacobian of SO(3): V in Exp([v;w]) = [Exp(w), V v].
inline Eigen::Matrix3d LeftJacobianSO3(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  const Eigen::Matrix3d W = Skew(w);
  if (theta < 1e-8) return Eigen::Matrix3d::Identity() + 0.5 * W;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1 - std::cos(theta)) / t2 * W +
         (theta - std::sin(theta)) / (t2 * theta) * W * W;
}

inline Eigen::Isometry3d ExpSE3(const Vector6d& xi) {
  const Eigen::Vector3d v = xi.head<3>();
  const Eigen::Vector3d w = xi.tail<3>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = ExpSO3(w);
  T.translation() = LeftJacobianSO3(w) * v;
  return T;
}

inline Vector6d LogSE3(const Eigen::Isometry3d& T) {
  const Eigen::Vector3d w = LogSO3(T.linear());
  Vector6d xi;
  xi.head<3>() = LeftJacobianSO3(w).inverse() * T.translation();
  xi.tail<3>() = w;
  return xi;
}

// Builds an isometry from a row-major 3x4 [R|t] (KITTI pose line).
inline Eigen::Isometry3d IsometryFromRowMajor3x4(const double* v) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = v[4 * r + c];
    T.translation()(r) = v[4 * r + 3];
  }
  return T;
}

}  // namespace dvso
