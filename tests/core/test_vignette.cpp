// core/vignette.h by hand: the radial position, the polynomial fall-off and the PNG the odometry reads.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "core/camera.h"
#include "core/vignette.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {

PinholeCamera MakeCamera(int width, int height, double f, double cx, double cy) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = f;
  c.cx = cx;
  c.cy = cy;
  return c;
}

PinholeCamera SmallCamera() { return MakeCamera(40, 30, 50, 20, 15); }

TEST(Vignette, RadialPositionIsZeroAtThePrincipalPointAndOneAtTheHalfDiagonal) {
  const RadialPosition rho(SmallCamera());  // half diagonal: sqrt(20^2 + 15^2) = 25
  EXPECT_DOUBLE_EQ(rho.Sq(20, 15), 0.0);
  EXPECT_DOUBLE_EQ(rho.Sq(40, 30), 1.0);
  EXPECT_DOUBLE_EQ(rho.Sq(20, 15 + 12.5), 0.25);
}

TEST(Vignette, PolynomialFallOffAndItsDerivativeByHand) {
  const RadialVignette v{{-0.3, 0.1}};
  EXPECT_DOUBLE_EQ(v.At(0.0), 1.0);
  EXPECT_NEAR(v.At(0.5), 1 - 0.3 * 0.5 + 0.1 * 0.25, 1e-15);
  EXPECT_NEAR(v.At(1.0), 0.8, 1e-15);
  EXPECT_DOUBLE_EQ(v.Derivative(0, 0.5), 0.5);
  EXPECT_DOUBLE_EQ(v.Derivative(1, 0.5), 0.25);
  // Finite differences in each coefficient.
  for (int i = 0; i < 2; ++i) {
    RadialVignette plus = v, minus = v;
    plus.coefficients[i] += 1e-6;
    minus.coefficients[i] -= 1e-6;
    EXPECT_NEAR((plus.At(0.7) - minus.At(0.7)) / 2e-6, v.Derivative(i, 0.7), 1e-8);
  }
  // Clamped at 0 (no negative light), where the derivative is 0 too.
  const RadialVignette dark{{-2.0}};
  EXPECT_EQ(dark.At(0.8), 0.0);
  EXPECT_EQ(dark.Derivative(0, 0.8), 0.0);
}

TEST(Vignette, ImageIsNormalisedToItsBrightestPixelAndRoundTripsThroughThePng) {
  const PinholeCamera c = SmallCamera();
  const RadialVignette falling{{-0.3}};
  const cv::Mat image = falling.Image(c);
  ASSERT_EQ(image.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(image.at<float>(15, 20), 1.0f);  // the principal point is a pixel
  EXPECT_NEAR(image.at<float>(0, 0), 1 - 0.3 * RadialPosition(c).Sq(0, 0), 1e-6);
  // A lens brighter off-centre: the brightest pixel (a corner) becomes 1.
  const RadialVignette rising{{0.2}};
  const cv::Mat brighter = rising.Image(c);
  double lo = 0, hi = 0;
  cv::minMaxLoc(brighter, &lo, &hi);
  EXPECT_FLOAT_EQ(static_cast<float>(hi), 1.0f);
  EXPECT_NEAR(brighter.at<float>(15, 20), 1.0 / (1 + 0.2 * RadialPosition(c).Sq(0, 0)), 1e-6);

  const std::string path = testing::ScratchDir("vignette_png") + "/vignette.png";
  falling.WritePng(path, c);
  const cv::Mat read = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(read.type(), CV_16UC1);
  EXPECT_EQ(read.at<uint16_t>(15, 20), 65535);
  EXPECT_NEAR(read.at<uint16_t>(29, 39), 65535.0 * (1 - 0.3 * RadialPosition(c).Sq(39, 29)), 0.51);
}

// The simulator's vignette.png keeps the values of its own formula from before core/vignette.h, at KITTI's
// size and principal point (not on a pixel).
TEST(Vignette, SimulatorLensPngHasTheValuesOfTheRendererFormula) {
  const PinholeCamera c = MakeCamera(1241, 376, 718.856, 607.1928, 185.2157);
  const double strength = 0.3;
  const std::string path = testing::ScratchDir("vignette_kitti") + "/vignette.png";
  RadialVignette{{-strength}}.WritePng(path, c);
  const cv::Mat read = cv::imread(path, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(read.type(), CV_16UC1);
  const double half_diagonal_sq = 0.25 * (1241.0 * 1241.0 + 376.0 * 376.0);
  int differing = 0;
  for (int y = 0; y < c.height; ++y)
    for (int x = 0; x < c.width; ++x) {
      const double r2 = (x - c.cx) * (x - c.cx) + (y - c.cy) * (y - c.cy);
      differing += read.at<uint16_t>(y, x) != std::lround(65535.0 * std::max(0.0, 1.0 - strength * r2 / half_diagonal_sq));
    }
  EXPECT_EQ(differing, 0);
}

}  // namespace
}  // namespace dvso
