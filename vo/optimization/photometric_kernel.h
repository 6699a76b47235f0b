// The one photometric residual kernel (DSO, paper eq. 5.1 / 5.8) shared by
// every user: the coarse tracker, the monocular initialiser, the immature
// point search and all residual kinds of the window (temporal, static stereo,
// virtual stereo). Header-only so the inner loops stay inlined.
//
//  - Huber norm with threshold gamma: rho(r) = r^2 for |r| <= gamma, else
//    2 gamma |r| - gamma^2; its IRLS weight is 1, resp. gamma / |r|.
//  - Gradient-dependent weight w_p = c^2 / (c^2 + |grad I|^2) at the sampled
//    position (DSO: interpolation errors grow with the gradient), treated as
//    a constant in the Jacobians.
//  - Geometric Jacobian of the sampled image value w.r.t. a left twist
//    xi = [v; w] of the relative pose target <- host: with the projected point
//    in normalised coordinates (un, vn), its inverse depth in the target d_t
//    and the image gradient scaled by the focal lengths (gx fx, gy fy):
//      d un / d xi = [d_t, 0, -d_t un, -un vn, 1 + un^2, -vn]
//      d vn / d xi = [0, d_t, -d_t vn, -(1 + vn^2), un vn, un]
#pragma once

#include <Eigen/Core>
#include <cmath>

namespace dvso::vo {

// Huber energy rho(r) and IRLS weight for one pixel residual.
inline void HuberWeightAndEnergy(float r, float gamma, float* weight, float* energy) {
  const float abs_r = std::abs(r);
  if (abs_r <= gamma) {
    *weight = 1.0f;
    *energy = r * r;
  } else {
    *weight = gamma / abs_r;
    *energy = 2.0f * gamma * abs_r - gamma * gamma;
  }
}

inline float HuberEnergy(float r, float gamma) {
  float weight, energy;
  HuberWeightAndEnergy(r, gamma, &weight, &energy);
  return energy;
}

// w_p = c^2 / (c^2 + gx^2 + gy^2) with c_sq = c^2.
inline float GradientWeight(float c_sq, float gx, float gy) { return c_sq / (c_sq + gx * gx + gy * gy); }

// The 6 pose entries of dI/dxi (header comment). dxf = gx fx, dyf = gy fy.
inline Eigen::Matrix<float, 6, 1> PoseJacobian(float dxf, float dyf, float un, float vn, float d_t) {
  Eigen::Matrix<float, 6, 1> J;
  J[0] = d_t * dxf;
  J[1] = d_t * dyf;
  J[2] = -d_t * (un * dxf + vn * dyf);
  J[3] = -un * vn * dxf - (1 + vn * vn) * dyf;
  J[4] = (1 + un * un) * dxf + un * vn * dyf;
  J[5] = -vn * dxf + un * dyf;
  return J;
}

// 8-dof Jacobian [pose (6), a, b] of r = I_new[p~] - e^a I_ref[p] - b, the
// frame-to-reference model of the tracker and the initialiser (ea = e^a).
inline Eigen::Matrix<float, 8, 1> PoseAffineJacobian(float dxf, float dyf, float un, float vn, float d_t, float ea,
                                                     float reference_intensity) {
  Eigen::Matrix<float, 8, 1> J;
  J.head<6>() = PoseJacobian(dxf, dyf, un, vn, d_t);
  J[6] = -ea * reference_intensity;
  J[7] = -1.0f;
  return J;
}

}  // namespace dvso::vo
