#include <gtest/gtest.h>

#include "tests/vo/frontend_test_scene.h"
#include "vo/frontend/pixel_selector.h"

namespace dvso::vo {
namespace {

TEST(FrontendSelector, ReachesDesiredDensityAndCoversImage) {
  testing::BoxScene scene;
  const PinholeCamera cam = testing::TestCamera(400, 300);
  cv::Mat img;
  scene.Render(cam, Eigen::Isometry3d::Identity(), &img, nullptr);
  const ImagePyramid pyr(img, cam);
  for (int desired : {500, 2000}) {
    PixelSelectorOptions opt;
    opt.desired_points = desired;
    const auto sel = SelectPixels(pyr, opt);
    EXPECT_GT(sel.size(), desired * 0.6) << desired;
    EXPECT_LT(sel.size(), desired * 1.3) << desired;
    // Coverage: every cell of a 4x4 grid receives points.
    int cells[4][4] = {};
    for (const auto& p : sel) {
      ASSERT_GE(p.x, opt.border);
      ASSERT_GE(p.y, opt.border);
      ASSERT_LT(p.x, cam.width - opt.border);
      ASSERT_LT(p.y, cam.height - opt.border);
      ++cells[p.y * 4 / cam.height][p.x * 4 / cam.width];
    }
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) EXPECT_GT(cells[i][j], desired / 16 / 5) << desired << " " << i << " " << j;
  }
}

TEST(FrontendSelector, WeakTextureUsesCoarseLevelsAndFlatImageGivesNothing) {
  const PinholeCamera cam = testing::TestCamera(320, 240);
  cv::Mat flat(cam.height, cam.width, CV_32F, cv::Scalar(100));
  EXPECT_TRUE(SelectPixels(ImagePyramid(flat, cam), PixelSelectorOptions{}).empty());
  // Left half: strong texture, right half: very smooth gradient ramp + faint texture.
  testing::BoxScene scene;
  cv::Mat img;
  scene.Render(cam, Eigen::Isometry3d::Identity(), &img, nullptr);
  cv::Mat smooth;
  cv::GaussianBlur(img, smooth, cv::Size(0, 0), 6.0);
  smooth.colRange(cam.width / 2, cam.width).copyTo(img.colRange(cam.width / 2, cam.width));
  const auto sel = SelectPixels(ImagePyramid(img, cam), PixelSelectorOptions{});
  int right = 0, coarse_right = 0;
  for (const auto& p : sel) {
    if (p.x > cam.width / 2 + 40) {
      ++right;
      if (p.level > 0) ++coarse_right;
    }
  }
  EXPECT_GT(right, 20);
  EXPECT_GT(coarse_right, 0);
}

TEST(FrontendPyramid, OddSizesAndLevelCameras) {
  PinholeCamera cam = testing::TestCamera(1241, 376);
  cv::Mat img(cam.height, cam.width, CV_8UC1);
  cv::randu(img, 0, 255);
  const ImagePyramid pyr(img, cam);
  ASSERT_GE(pyr.num_levels(), 4);
  EXPECT_EQ(pyr.width(1), 620);
  EXPECT_EQ(pyr.height(1), 188);
  EXPECT_EQ(pyr.width(3), 155);
  // A level-0 point projects to the consistent level-l position.
  const Eigen::Vector3d X(0.7, -0.3, 4.0);
  const Eigen::Vector2d p0 = pyr.camera(0).Project(X);
  for (int l = 1; l < pyr.num_levels(); ++l) {
    const Eigen::Vector2d pl = pyr.camera(l).Project(X);
    const double s = 1.0 / (1 << l);
    EXPECT_NEAR(pl.x(), (p0.x() + 0.5) * s - 0.5, 1e-9);
    EXPECT_NEAR(pl.y(), (p0.y() + 0.5) * s - 0.5, 1e-9);
  }
  // Gradient: central difference of a ramp.
  cv::Mat ramp(cam.height, cam.width, CV_32F);
  for (int y = 0; y < ramp.rows; ++y)
    for (int x = 0; x < ramp.cols; ++x) ramp.at<float>(y, x) = 0.5f * x + 0.25f * y;
  const ImagePyramid rp(ramp, cam);
  const Eigen::Vector3f v = rp.level(0).Interpolate(100.25f, 50.5f);
  EXPECT_NEAR(v[0], 0.5 * 100.25 + 0.25 * 50.5, 1e-3);
  EXPECT_NEAR(v[1], 0.5, 1e-5);
  EXPECT_NEAR(v[2], 0.25, 1e-5);
  EXPECT_NEAR(rp.level(1).Interpolate(40.f, 30.f)[1], 1.0, 1e-4);  // twice the slope per coarse pixel
}

}  // namespace
}  // namespace dvso::vo
