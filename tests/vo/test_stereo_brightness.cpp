// The stereo pair's brightness transfer (vo/frame/stereo_brightness.h): the
// line fit by hand, the quantile estimate on a synthetic pair with a known
// transfer and disparity, and the options that switch it off.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/error.h"
#include "tests/vo/test_backend_util.h"
#include "vo/frame/stereo_brightness.h"

namespace dvso::vo {
namespace {

using testing::ImageFromFunction;
using testing::MakePyramid;
using testing::SmallCamera;

TEST(StereoBrightness, LineFitRecoversAnExactTransfer) {
  std::vector<double> x, y;
  for (int i = 0; i < 20; ++i) {
    x.push_back(10.0 + 11.0 * i);
    y.push_back(1.25 * x.back() - 7.0);
  }
  const auto fit = FitBrightnessTransfer(x, y, 4.0, 3.0);
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(fit->gain, 1.25, 1e-9);
  EXPECT_NEAR(fit->bias, -7.0, 1e-7);
}

TEST(StereoBrightness, LineFitHandComputedOrthogonalLeastSquares) {
  // Points (0, 1), (1, 2), (2, 4): means 1 and 7/3; centred sums Sxx = 2, Syy = 42/9, Sxy = 3.
  // Orthogonal slope (Syy - Sxx + sqrt((Syy - Sxx)^2 + 4 Sxy^2)) / (2 Sxy) = (24/9 + sqrt((24/9)^2 + 36)) / 6
  // = 1.538762...; the ordinary least-squares slope would be Sxy / Sxx = 1.5. Residuals stay below the Huber threshold.
  const auto fit = FitBrightnessTransfer({0, 1, 2}, {1, 2, 4}, 4.0, 3.0);
  ASSERT_TRUE(fit.has_value());
  const double slope = (24.0 / 9.0 + std::sqrt(24.0 / 9.0 * 24.0 / 9.0 + 36.0)) / 6.0;
  EXPECT_NEAR(fit->gain, slope, 1e-12);
  EXPECT_NEAR(fit->gain, 1.538762, 1e-6);
  EXPECT_NEAR(fit->bias, 7.0 / 3.0 - slope, 1e-12);
}

// With the same noise on both sides the orthogonal slope stays at the true gain where the
// ordinary one shrinks by var(noise) / var(x) (errors in variables).
TEST(StereoBrightness, LineFitIsNotAttenuatedByNoiseInTheLeftIntensities) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> signal(60.0, 100.0);  // std 11.5: a low-contrast world
  std::normal_distribution<double> noise(0.0, 3.0);
  std::vector<double> x, y;
  for (int i = 0; i < 200000; ++i) {
    const double s = signal(rng);
    x.push_back(s + noise(rng));
    y.push_back(1.1 * s + 4.0 + noise(rng));
  }
  const auto fit = FitBrightnessTransfer(x, y, 1e9, 3.0);
  ASSERT_TRUE(fit.has_value());
  // Ordinary least squares would give 1.1 * 133.3 / (133.3 + 9) = 1.030. The orthogonal fit is consistent
  // for any gain when both sides carry the same noise variance, as here (the right image's noise is
  // added after its gain).
  EXPECT_NEAR(fit->gain, 1.1, 0.005);
}

TEST(StereoBrightness, HuberWeightsKeepAGrossOutlierFromPullingTheLine) {
  std::vector<double> x, y;
  for (int i = 0; i < 40; ++i) {
    x.push_back(20.0 + 5.0 * i);
    y.push_back(0.9 * x.back() + 3.0);
  }
  x.push_back(100.0);
  y.push_back(250.0);  // a wrong match: 157 grey levels off the line
  const auto robust = FitBrightnessTransfer(x, y, 4.0, 3.0);
  const auto plain = FitBrightnessTransfer(x, y, 1e9, 3.0);  // no reweighting
  ASSERT_TRUE(robust.has_value() && plain.has_value());
  EXPECT_NEAR(robust->gain, 0.9, 0.01);
  EXPECT_NEAR(robust->bias, 3.0, 1.0);
  EXPECT_GT(std::abs(plain->bias - 3.0), 2.0);  // the outlier does pull an unweighted fit
}

TEST(StereoBrightness, LineFitRefusesTooFewFlatOrImplausibleSamples) {
  EXPECT_FALSE(FitBrightnessTransfer({1, 2}, {1, 2}, 4.0, 3.0).has_value());                // too few
  EXPECT_FALSE(FitBrightnessTransfer({5, 5, 5, 5}, {1, 2, 3, 4}, 4.0, 3.0).has_value());    // no spread in x
  EXPECT_FALSE(FitBrightnessTransfer({0, 1, 2, 3}, {0, 5, 10, 15}, 4.0, 3.0).has_value());  // gain 5 > 3
  EXPECT_FALSE(FitBrightnessTransfer({0, 1, 2, 3}, {3, 2, 1, 0}, 4.0, 3.0).has_value());    // negative gain
}

// A textured image (smoothed noise, the scale of street texture) and the
// right view of a fronto-parallel scene at `disparity` px through (gain, bias).
struct Pair {
  ImagePyramidPtr left, right;
};
Pair MakePair(double disparity, double gain, double bias) {
  const PinholeCamera camera = SmallCamera(400, 200);
  cv::Mat noise(camera.height, camera.width + 64, CV_32FC1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(0.f, 255.f);
  for (int y = 0; y < noise.rows; ++y)
    for (int x = 0; x < noise.cols; ++x) noise.at<float>(y, x) = u(rng);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 20, 230, cv::NORM_MINMAX);
  auto scene = [&](double x, double y) {  // bilinear read of the texture, x shifted into its margin
    const double xs = x + 32.0;
    const int ix = static_cast<int>(std::floor(xs)), iy = static_cast<int>(y);
    const double t = xs - ix;
    return (1 - t) * noise.at<float>(iy, ix) + t * noise.at<float>(iy, ix + 1);
  };
  Pair p;
  p.left = MakePyramid(ImageFromFunction(camera, [&](double x, double y) { return static_cast<float>(scene(x, y)); }),
                       camera);
  // Right camera at +baseline: the scene point at left x appears at x - d, i.e. I_R(x) = T(I_L(x + d)).
  p.right = MakePyramid(ImageFromFunction(camera,
                                          [&](double x, double y) {
                                            return static_cast<float>(gain * scene(x + disparity, y) + bias);
                                          }),
                        camera);
  return p;
}

TEST(StereoBrightness, QuantilesRecoverTheTransferOfAShiftedPair) {
  for (const auto& [gain, bias] : {std::pair{1.2, 10.0}, std::pair{0.85, -6.0}, std::pair{1.0, 0.0}}) {
    const Pair p = MakePair(9.5, gain, bias);
    const StereoBrightness t = EstimateStereoBrightness(p.left->level(0), p.right->level(0), {});
    EXPECT_NEAR(t.gain, gain, 0.02) << gain << " " << bias;
    EXPECT_NEAR(t.bias, bias, 2.5) << gain << " " << bias;
  }
}

TEST(StereoBrightness, SwitchedOffOrFlatImagesGiveTheIdentity) {
  const Pair p = MakePair(9.5, 1.2, 10.0);
  StereoBrightnessOptions off;
  off.estimate = false;
  const StereoBrightness t = EstimateStereoBrightness(p.left->level(0), p.right->level(0), off);
  EXPECT_EQ(t.gain, 1.0);
  EXPECT_EQ(t.bias, 0.0);
  const PinholeCamera camera = SmallCamera(64, 48);
  const ImagePyramidPtr flat = MakePyramid(ImageFromFunction(camera, [](double, double) { return 90.f; }), camera);
  const StereoBrightness f = EstimateStereoBrightness(flat->level(0), flat->level(0), {});
  EXPECT_EQ(f.gain, 1.0);
  EXPECT_EQ(f.bias, 0.0);
}

TEST(StereoBrightness, OptionsAreChecked) {
  StereoBrightnessOptions o;
  EXPECT_NO_THROW(o.Check());
  o.min_quantile = 0.9;
  o.max_quantile = 0.5;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.max_gain_ratio = 1.0;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.max_matching_passes = 0;
  EXPECT_THROW(o.Check(), Error);
  o = {};
  o.max_radial = 1.0;
  EXPECT_THROW(o.Check(), Error);
}

TEST(StereoBrightness, ChangeIsMeasuredOverTheIntensitiesThatOccur) {
  // Gain and bias trade against each other: x1.01 - 1.2 is within 0.2 of the identity on [60, 120]
  // although its bias alone moved by 1.2.
  const StereoBrightness a{1.0, 0.0}, b{1.01, -1.2};
  EXPECT_NEAR(BrightnessTransferChange(a, b, 60, 120), 0.6, 1e-12);  // |0.01 * 60 - 1.2| = 0.6, |1.2 - 1.2| = 0
  EXPECT_NEAR(BrightnessTransferChange(a, b, 0, 255), 1.35, 1e-12);  // |0.01 * 255 - 1.2| = 1.35
  EXPECT_EQ(BrightnessTransferChange(a, a, 0, 255), 0.0);
}

TEST(StereoBrightness, UnclippedRangeExcludesTheDarkestAndBrightestIntensities) {
  // A ramp from 10 to 250 with a saturated block and a black block: those two, and only those,
  // fall outside the range.
  const PinholeCamera camera = SmallCamera(64, 48);
  const ImagePyramidPtr image = MakePyramid(ImageFromFunction(camera, [](double x, double y) {
                                              if (x < 8 && y < 8) return 0.f;
                                              if (x > 55 && y > 39) return 255.f;
                                              return static_cast<float>(10.0 + 240.0 * x / 63.0);
                                            }),
                                            camera);
  const UnclippedRange range = UnclippedIntensityRange(image->level(0));
  EXPECT_FLOAT_EQ(range.low, 0.f + UnclippedRange::kClipMargin);
  EXPECT_FLOAT_EQ(range.high, 255.f - UnclippedRange::kClipMargin);
  EXPECT_FALSE(range.Contains(0.f));
  EXPECT_FALSE(range.Contains(0.4f));
  EXPECT_FALSE(range.Contains(255.f));
  EXPECT_TRUE(range.Contains(10.f));
  EXPECT_TRUE(range.Contains(250.f));
}

TEST(StereoBrightness, RadialFitRecoversAVignettingDifference) {
  // y = 1.1 (1 + 0.25 rho^2) x - 3 + noise: a right lens whose corners are 25 % brighter relative to the left.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> intensity(20, 200), position(0, 1);
  std::normal_distribution<double> noise(0, 1.0);
  std::vector<double> x, y, rho_sq, y_flat;
  for (int i = 0; i < 4000; ++i) {
    x.push_back(intensity(rng));
    rho_sq.push_back(position(rng));
    y.push_back(1.1 * (1 + 0.25 * rho_sq.back()) * x.back() - 3 + noise(rng));
    y_flat.push_back(1.1 * x.back() - 3 + noise(rng));
  }
  const std::optional<StereoBrightness> t = FitRadialBrightnessTransfer(x, y, rho_sq, 4.0, 3.0, 0.8);
  ASSERT_TRUE(t.has_value());
  EXPECT_NEAR(t->gain, 1.1, 0.01);
  EXPECT_NEAR(t->radial, 0.25, 0.01);
  EXPECT_NEAR(t->bias, -3, 1.0);
  EXPECT_NEAR(t->Gain(1.0), 1.1 * 1.25, 0.01);
  // The line fit alone leaves a position-dependent error of up to 1.1 * 0.25 * 200 / 2 grey levels.
  const std::optional<StereoBrightness> line = FitBrightnessTransfer(x, y, 4.0, 3.0);
  ASSERT_TRUE(line.has_value());
  EXPECT_EQ(line->radial, 0.0);
  // Without a difference the radial term stays near 0; beyond max_radial the fit is refused.
  const std::optional<StereoBrightness> flat = FitRadialBrightnessTransfer(x, y_flat, rho_sq, 4.0, 3.0, 0.8);
  ASSERT_TRUE(flat.has_value());
  EXPECT_NEAR(flat->radial, 0.0, 0.005);
  EXPECT_NEAR(flat->gain, 1.1, 0.005);
  EXPECT_FALSE(FitRadialBrightnessTransfer(x, y, rho_sq, 4.0, 3.0, 0.2).has_value());
}

TEST(StereoBrightness, RadialTermAndTheLineAtItAreTheJointFitsTwoSteps) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> intensity(20, 200), position(0, 1);
  std::normal_distribution<double> noise(0, 1.0);
  std::vector<double> x, y, rho_sq;
  for (int i = 0; i < 3000; ++i) {
    x.push_back(intensity(rng));
    rho_sq.push_back(position(rng));
    y.push_back(0.9 * (1 - 0.2 * rho_sq.back()) * x.back() + 4 + noise(rng));
  }
  const std::optional<double> radial = FitRadialTerm(x, y, rho_sq, 4.0, 0.8);
  ASSERT_TRUE(radial.has_value());
  EXPECT_NEAR(*radial, -0.2, 0.01);
  const std::optional<StereoBrightness> at = FitBrightnessTransferAtRadial(x, y, rho_sq, *radial, 4.0, 3.0);
  ASSERT_TRUE(at.has_value());
  EXPECT_EQ(at->radial, *radial);
  EXPECT_NEAR(at->gain, 0.9, 0.01);
  EXPECT_NEAR(at->bias, 4.0, 1.0);
  // A radial term given from elsewhere (the pool) is used as given: gain and bias absorb what they can.
  const std::optional<StereoBrightness> at_zero = FitBrightnessTransferAtRadial(x, y, rho_sq, 0.0, 4.0, 3.0);
  ASSERT_TRUE(at_zero.has_value());
  EXPECT_EQ(at_zero->radial, 0.0);
  EXPECT_NEAR(at_zero->gain, 0.9 * (1 - 0.2 * 0.5), 0.02);  // the mean fall-off 0.2 * E[rho^2] goes into the gain
  EXPECT_FALSE(FitRadialTerm(x, y, rho_sq, 4.0, 0.1).has_value());  // |radial| 0.2 > max_radial
}

TEST(StereoBrightness, RadialTermPoolIsTheMedianOfTheLastKeyframesAndTheCurrentOne) {
  RadialTermPool pool(3);
  EXPECT_EQ(pool.MedianWith(0.4), 0.4);  // nothing stored: the keyframe's own fit
  pool.Add(0.30);
  EXPECT_NEAR(pool.MedianWith(0.10), 0.20, 1e-12);  // even count: mean of the middle two
  pool.Add(0.26);
  EXPECT_NEAR(pool.MedianWith(-0.50), 0.26, 1e-12);  // one outlying keyframe does not move it far
  pool.Add(0.28);
  pool.Add(0.0);  // the capacity is 3: 0.30 goes
  EXPECT_EQ(pool.size(), 3);
  // stored {0.26, 0.28, 0.0} + 0.27 -> middle two 0.26, 0.27
  EXPECT_NEAR(pool.MedianWith(0.27), 0.265, 1e-12);
  EXPECT_NEAR(pool.Median(), 0.26, 1e-12);  // {0.26, 0.28, 0.0}
  RadialTermPool none(0);  // capacity 0: each keyframe alone (the behaviour of session 28)
  none.Add(0.3);
  EXPECT_EQ(none.size(), 0);
  EXPECT_EQ(none.MedianWith(-0.1), -0.1);
  EXPECT_THROW(RadialTermPool(-1), Error);
  EXPECT_THROW(none.Median(), Error);  // nothing stored
  EXPECT_THROW(pool.Add(std::nan("")), Error);
  StereoBrightnessOptions o;
  o.radial_pool_keyframes = -1;
  EXPECT_THROW(o.Check(), Error);
}

TEST(StereoBrightness, RadialPositionIsZeroAtThePrincipalPointAndOneInTheCorners) {
  PinholeCamera camera;
  camera.cx = 320.0;
  camera.cy = 240.0;
  camera.width = 640;
  camera.height = 480;
  const RadialPosition rho(camera);
  EXPECT_EQ(rho.Sq(320.0, 240.0), 0.0);
  EXPECT_NEAR(rho.Sq(0.0, 0.0), 1.0, 1e-12);
  EXPECT_NEAR(rho.Sq(640.0, 240.0), 320.0 * 320.0 / (400.0 * 400.0), 1e-12);
  // The residual's float version is the same formula.
  const BasicRadialPosition<float> rho_float(camera);
  EXPECT_NEAR(rho_float.Sq(10.0f, 20.0f), rho.Sq(10.0, 20.0), 1e-6);
  // The change between two transfers is taken over the corners too: radial 0.1 at I = 100 is 10.
  EXPECT_NEAR(BrightnessTransferChange({1.0, 0.0, 0.0}, {1.0, 0.0, 0.1}, 50, 100), 10.0, 1e-12);
}

}  // namespace
}  // namespace dvso::vo
