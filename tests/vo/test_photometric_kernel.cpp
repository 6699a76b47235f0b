// The shared photometric kernel (vo/optimization/photometric_kernel.h): Huber
// and gradient weights by hand, the pose Jacobian against finite differences
// of the projection under a left twist, and the tracker's affine entries.
#include <gtest/gtest.h>

#include "core/lie.h"
#include "vo/optimization/photometric_kernel.h"

namespace dvso::vo {
namespace {

TEST(PhotometricKernel, HuberAndGradientWeightByHand) {
  float w, e;
  HuberWeightAndEnergy(3.0f, 9.0f, &w, &e);
  EXPECT_FLOAT_EQ(w, 1.0f);
  EXPECT_FLOAT_EQ(e, 9.0f);
  HuberWeightAndEnergy(-18.0f, 9.0f, &w, &e);
  EXPECT_FLOAT_EQ(w, 0.5f);
  EXPECT_FLOAT_EQ(e, 2 * 9 * 18 - 81);  // 2 gamma |r| - gamma^2
  EXPECT_FLOAT_EQ(HuberEnergy(9.0f, 9.0f), 81.0f);  // continuous at |r| = gamma
  EXPECT_FLOAT_EQ(GradientWeight(2500.0f, 30.0f, 40.0f), 2500.0f / (2500.0f + 2500.0f));
}

TEST(PhotometricKernel, PoseJacobianMatchesFiniteDifferencesOfTheProjection) {
  // Image gradient (gx, gy) in pixels; I(u, v) ~ gx u + gy v locally, so
  // dI/dxi = gx fx d un/dxi + gy fy d vn/dxi.
  const double fx = 500, fy = 480, gx = 0.7, gy = -1.3;
  const Eigen::Vector3d X(1.2, -0.4, 6.0);  // point in the target camera
  const double un = X.x() / X.z(), vn = X.y() / X.z();
  const Eigen::Matrix<float, 6, 1> J = PoseJacobian(static_cast<float>(gx * fx), static_cast<float>(gy * fy),
                                                    static_cast<float>(un), static_cast<float>(vn),
                                                    static_cast<float>(1.0 / X.z()));
  const double h = 1e-6;
  for (int i = 0; i < 6; ++i) {
    Vector6d xi = Vector6d::Zero();
    xi[i] = h;
    const Eigen::Vector3d Xp = ExpSE3(xi) * X;
    const Eigen::Vector3d Xm = ExpSE3(-xi) * X;
    const double dun = (Xp.x() / Xp.z() - Xm.x() / Xm.z()) / (2 * h);
    const double dvn = (Xp.y() / Xp.z() - Xm.y() / Xm.z()) / (2 * h);
    EXPECT_NEAR(J[i], gx * fx * dun + gy * fy * dvn, 1e-3 * (1 + std::abs(J[i]))) << "component " << i;
  }
  const Eigen::Matrix<float, 8, 1> J8 = PoseAffineJacobian(1.0f, 2.0f, 0.1f, 0.2f, 0.5f, 1.5f, 40.0f);
  EXPECT_FLOAT_EQ(J8[6], -60.0f);  // d(I - e^a I_ref - b)/da = -e^a I_ref
  EXPECT_FLOAT_EQ(J8[7], -1.0f);
  EXPECT_TRUE(J8.head<6>().isApprox(PoseJacobian(1.0f, 2.0f, 0.1f, 0.2f, 0.5f)));
}

}  // namespace
}  // namespace dvso::vo
