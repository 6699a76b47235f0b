// Monocular initialisation on a turning start (KITTI-like: a few degrees of
// yaw per frame with little parallax). A yaw and a sideways translation over
// flat inverse depths produce nearly the same flow; the initialiser must take
// the rotation for a rotation (it used to mistake it for translation, which
// then propagated through the constant-velocity prediction).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/lie.h"
#include "tests/vo/frontend_test_scene.h"
#include "vo/frontend/mono_initializer.h"

namespace dvso::vo {
namespace {

using testing::BoxScene;
using testing::TestCamera;

// Camera-to-world pose of frame i: yaw of yaw_deg per frame, moving forward
// along the current heading by step metres per frame.
Eigen::Isometry3d TurningPose(int i, double yaw_deg, double step) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  for (int k = 1; k <= i; ++k) {
    const double heading = (k - 0.5) * yaw_deg * M_PI / 180.0;
    position += step * Eigen::Vector3d(std::sin(heading), 0.0, std::cos(heading));
  }
  T.linear() = ExpSO3(Eigen::Vector3d(0.0, i * yaw_deg * M_PI / 180.0, 0.0));
  T.translation() = position + Eigen::Vector3d(0.0, 0.0, -4.0);  // start well inside the box
  return T;
}

TEST(FrontendMonoInit, TurningStartRotationIsNotTakenForTranslation) {
  BoxScene scene;
  const PinholeCamera cam = TestCamera();
  const double yaw_deg = 3.5, step = 0.1;
  const Eigen::Isometry3d T_world_first = TurningPose(0, yaw_deg, step);
  cv::Mat image;
  scene.Render(cam, T_world_first, &image, nullptr);
  MonoInitializer init(MonoInitializerOptions{}, PixelSelectorOptions{}, CoarseTrackerOptions{});
  init.SetFirstFrame(std::make_shared<ImagePyramid>(image, cam));
  bool done = false;
  int frames = 0;
  for (int i = 1; i <= 12 && !done; ++i) {
    const Eigen::Isometry3d T_world_i = TurningPose(i, yaw_deg, step);
    scene.Render(cam, T_world_i, &image, nullptr);
    const ImagePyramid frame(image, cam);
    done = init.AddFrame(frame);
    ASSERT_FALSE(init.failed()) << "frame " << i;
    ++frames;
    // Rotation of every frame relative to the first: the yaw, not a sideways translation.
    const Eigen::Isometry3d T_true = T_world_i.inverse() * T_world_first;  // frame <- first
    const Eigen::Isometry3d& T_est = init.T_last_first();
    const double rot_err_deg = RotationAngle(T_est.linear() * T_true.linear().transpose()) * 180.0 / M_PI;
    EXPECT_LT(rot_err_deg, 0.25 * yaw_deg) << "frame " << i;
    // Translation direction (the scale is free).
    if (T_est.translation().norm() > 1e-9) {
      const double cos_angle =
          T_est.translation().normalized().dot(T_true.translation().normalized());
      EXPECT_GT(cos_angle, std::cos(15.0 * M_PI / 180.0)) << "frame " << i;
    }
  }
  EXPECT_TRUE(done) << "not initialised after " << frames << " frames";
}

// A frame that makes the optimisation diverge (here: non-finite intensities) fails the
// initialiser, and the pose it keeps is the last finite one: the System places the restart
// with T_last_first(), and a non-finite pose there would make every later pose non-finite.
TEST(FrontendMonoInit, DivergenceKeepsTheLastFinitePose) {
  BoxScene scene;
  const PinholeCamera cam = TestCamera();
  cv::Mat image;
  scene.Render(cam, TurningPose(0, 0.0, 0.1), &image, nullptr);
  MonoInitializer init(MonoInitializerOptions{}, PixelSelectorOptions{}, CoarseTrackerOptions{});
  init.SetFirstFrame(std::make_shared<ImagePyramid>(image, cam));
  scene.Render(cam, TurningPose(1, 0.0, 0.1), &image, nullptr);
  ASSERT_FALSE(init.AddFrame(ImagePyramid(image, cam)));
  ASSERT_FALSE(init.failed());
  const Eigen::Isometry3d before = init.T_last_first();
  cv::Mat broken(cam.height, cam.width, CV_32FC1, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  EXPECT_FALSE(init.AddFrame(ImagePyramid(broken, cam)));
  EXPECT_TRUE(init.failed());
  EXPECT_TRUE(init.T_last_first().matrix().allFinite());
  EXPECT_TRUE(init.T_last_first().isApprox(before));
}

}  // namespace
}  // namespace dvso::vo
