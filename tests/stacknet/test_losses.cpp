// Each loss term of paper eq. (2)-(6) against values computed by hand on tiny
// tensors, the warp against known shifts, and eq. (1)'s weighting.
#include <gtest/gtest.h>

#include <cmath>

#include "stacknet/losses.h"
#include "stacknet/post_process.h"
#include "stacknet/warping.h"

namespace dvso::stacknet {
namespace {

torch::Tensor Map(std::vector<float> values, int64_t h, int64_t w) {
  return torch::tensor(values).view({1, 1, h, w});
}

TEST(Warping, IntegerAndHalfPixelShiftsOfARamp) {
  // I(x) = x on a 5-wide image; offset 1 px = 0.2 of the width.
  const torch::Tensor ramp = Map({0, 1, 2, 3, 4}, 1, 5);
  const torch::Tensor shifted = WarpHorizontal(ramp, torch::full({1, 1, 1, 5}, 0.2));
  const torch::Tensor expected = Map({1, 2, 3, 4, 4}, 1, 5);  // border padding at the right end
  EXPECT_TRUE(torch::allclose(shifted, expected, 1e-5, 1e-5)) << shifted;
  const torch::Tensor half = WarpHorizontal(ramp, torch::full({1, 1, 1, 5}, -0.1));
  EXPECT_TRUE(torch::allclose(half, Map({0, 0.5, 1.5, 2.5, 3.5}, 1, 5), 1e-5, 1e-5)) << half;
}

TEST(Warping, ReconstructLeftSamplesRightAtXMinusDisparity) {
  // Right image R(x) = 10 x; left disparity 2 px (W = 8 -> 0.25): L_recons(x) = R(x - 2).
  const torch::Tensor right = Map({0, 10, 20, 30, 40, 50, 60, 70}, 1, 8);
  const torch::Tensor recons = ReconstructLeft(right, torch::full({1, 1, 1, 8}, 0.25));
  EXPECT_TRUE(torch::allclose(recons, Map({0, 0, 0, 10, 20, 30, 40, 50}, 1, 8), 1e-4, 1e-4)) << recons;
}

TEST(Losses, OcclusionIsMeanAbsoluteDisparity) {
  EXPECT_NEAR(OcclusionLoss(Map({0.1f, -0.2f, 0.3f, 0.4f}, 2, 2)).item<double>(), 0.25, 1e-7);
}

TEST(Losses, BerHuSupervisedHandComputed) {
  const torch::Tensor prediction = Map({0.5f, 1.0f, 2.0f, 3.0f}, 1, 4);
  const torch::Tensor label = Map({9.0f, 1.5f, 1.0f, 1.0f}, 1, 4);
  const torch::Tensor mask = Map({0, 1, 1, 1}, 1, 4);
  // Residuals -0.5, 1, 2 (pixel 0 unlabelled); c = 0.2 * 2 = 0.4: all above c.
  // (0.25 + 0.16) / 0.8 = 0.5125, (1 + 0.16) / 0.8 = 1.45, (4 + 0.16) / 0.8 = 5.2 -> mean 2.3875.
  EXPECT_NEAR(SupervisedLoss(prediction, label, mask, 0.2).item<double>(), 2.3875, 1e-6);
  // c = 0.6 * 2 = 1.2: 0.5 and 1 are L1, 2 is (4 + 1.44) / 2.4 -> (0.5 + 1 + 2.266667) / 3.
  EXPECT_NEAR(SupervisedLoss(prediction, label, mask, 0.6).item<double>(), (0.5 + 1.0 + 5.44 / 2.4) / 3.0, 1e-6);
  // No labelled pixel: no supervised signal.
  EXPECT_EQ(SupervisedLoss(prediction, label, torch::zeros_like(mask), 0.2).item<double>(), 0.0);
  // Relative: labels 1.5, 1, 1 (mean 7/6); residuals -0.5, 1, 2 -> -0.5 * (7/6) / 1.5 = -7/18, 7/6, 7/3;
  // c = 0.6 * 7/3 = 1.4: 7/18 and 7/6 are L1, 7/3 is ((7/3)^2 + 1.96) / 2.8.
  const double r3 = 7.0 / 3.0;
  EXPECT_NEAR(SupervisedLoss(prediction, label, mask, 0.6, /*relative=*/true).item<double>(),
              (7.0 / 18.0 + 7.0 / 6.0 + (r3 * r3 + 1.96) / 2.8) / 3.0, 1e-6);
}

TEST(Losses, BerHuGradientIsSignInTheL1PartAndResidualOverCInTheL2Part) {
  const torch::Tensor prediction = Map({1.0f, 3.0f}, 1, 2).requires_grad_(true);
  const torch::Tensor label = Map({0.9f, 1.0f}, 1, 2);
  SupervisedLoss(prediction, label, torch::ones_like(label), 0.2).backward();
  // c = 0.4: r = 0.1 -> d/dr = 1 / 2 (mean); r = 2 -> r / c / 2 = 2.5.
  EXPECT_NEAR(prediction.grad()[0][0][0][0].item<double>(), 0.5, 1e-5);
  EXPECT_NEAR(prediction.grad()[0][0][0][1].item<double>(), 2.5, 1e-5);
}

TEST(Losses, LeftRightConsistencyHandComputed) {
  // d_r(x) = 0.01 x, d_l = 0.2 (1 px of 5): d_r(x - 1) = 0, 0, 0.01, 0.02, 0.03 (border).
  const torch::Tensor right = Map({0, 0.01f, 0.02f, 0.03f, 0.04f}, 1, 5);
  const torch::Tensor left = torch::full({1, 1, 1, 5}, 0.2);
  EXPECT_NEAR(LeftRightConsistencyLoss(left, right, -1.0).item<double>(), (0.2 + 0.2 + 0.19 + 0.18 + 0.17) / 5, 1e-6);
  // Right term: d_l(x + d_r(x)) with constant d_l = 0.2: |0.01 x - 0.2|.
  EXPECT_NEAR(LeftRightConsistencyLoss(right, left, +1.0).item<double>(), (0.2 + 0.19 + 0.18 + 0.17 + 0.16) / 5, 1e-6);
}

TEST(Losses, SecondOrderEdgeAwareSmoothnessHandComputed) {
  const torch::Tensor d = Map({0, 1, 4, 0, 0, 0, 1, 1, 1}, 3, 3);
  // Flat image: weights 1. d_xx rows: 2, 0, 0 -> 2/3; d_yy columns: 1, 2, 5 -> 8/3.
  EXPECT_NEAR(SmoothnessLoss(d, torch::zeros({1, 3, 3, 3})).item<double>(), 10.0 / 3.0, 1e-6);
  // Channel 0 has I_xx = 1 in row 0 and I_yy = 1 in column 2, channel 1 is flat:
  // the channel mean is 0.5, so those terms are weighted by exp(-0.5).
  torch::Tensor image = torch::zeros({1, 2, 3, 3});
  image[0][0][0][2] = 1.0;
  const double w = std::exp(-0.5);
  EXPECT_NEAR(SmoothnessLoss(d, image).item<double>(), (2 * w) / 3.0 + (1 + 2 + 5 * w) / 3.0, 1e-6);
}

TEST(Losses, SsimOfConstantPatchesAndPhotometricTerm) {
  // Constant 3x3 patches a = 0.5, b = 0.25: sigmas vanish, SSIM = (2ab + C1) / (a^2 + b^2 + C1).
  const double c1 = 1e-4;
  const double ssim = (2 * 0.5 * 0.25 + c1) / (0.25 + 0.0625 + c1);
  const torch::Tensor a = torch::full({1, 1, 3, 3}, 0.5);
  const torch::Tensor b = torch::full({1, 1, 3, 3}, 0.25);
  EXPECT_NEAR(SsimMap(a, b).item<double>(), ssim, 1e-6);
  EXPECT_NEAR(PhotometricLoss(a, b, 0.84).item<double>(), 0.84 * (1 - ssim) / 2 + 0.16 * 0.25, 1e-6);
  EXPECT_NEAR(PhotometricLoss(a, a, 0.84).item<double>(), 0.0, 1e-6);
}

TEST(Losses, SsimOfAStructuredPatchMatchesTheDefinition) {
  // x = 0..8 / 8, y = x^2: compute the single 3x3 SSIM value with plain doubles.
  std::vector<float> xv, yv;
  for (int i = 0; i < 9; ++i) {
    xv.push_back(i / 8.0f);
    yv.push_back((i / 8.0f) * (i / 8.0f));
  }
  double mx = 0, my = 0, sxx = 0, syy = 0, sxy = 0;
  for (int i = 0; i < 9; ++i) mx += xv[i] / 9.0, my += yv[i] / 9.0;
  for (int i = 0; i < 9; ++i) {
    sxx += double(xv[i]) * xv[i] / 9.0;
    syy += double(yv[i]) * yv[i] / 9.0;
    sxy += double(xv[i]) * yv[i] / 9.0;
  }
  sxx -= mx * mx, syy -= my * my, sxy -= mx * my;
  const double c1 = 1e-4, c2 = 9e-4;
  const double expected = (2 * mx * my + c1) * (2 * sxy + c2) / ((mx * mx + my * my + c1) * (sxx + syy + c2));
  EXPECT_NEAR(SsimMap(Map(xv, 3, 3), Map(yv, 3, 3)).item<double>(), expected, 1e-5);
}

TEST(Losses, TotalLossWeightsTermsPerScaleAsEquationOne) {
  torch::manual_seed(3);
  StereoBatch batch;
  batch.left = torch::rand({1, 3, 32, 64});
  batch.right = torch::rand({1, 3, 32, 64});
  batch.left_label = torch::rand({1, 1, 32, 64}) * 0.2;
  batch.right_label = torch::rand({1, 1, 32, 64}) * 0.2;
  batch.left_mask = (torch::rand({1, 1, 32, 64}) > 0.7).to(torch::kFloat32);
  batch.right_mask = (torch::rand({1, 1, 32, 64}) > 0.7).to(torch::kFloat32);
  DisparityPyramid d;
  for (int s = 0; s < 4; ++s) {
    d.left.push_back(torch::rand({1, 1, 32 >> s, 64 >> s}) * 0.2);
    d.right.push_back(torch::rand({1, 1, 32 >> s, 64 >> s}) * 0.2);
  }
  const LossOptions options;
  // Smoothness only: sum_s 0.1 / 2^s (L_smooth^l + L_smooth^r).
  LossSwitches smooth_only{false, false, false, true, false};
  double expected = 0;
  for (int s = 0; s < 4; ++s) {
    const torch::Tensor l = torch::avg_pool2d(batch.left, {1 << s, 1 << s}, {1 << s, 1 << s});
    const torch::Tensor r = torch::avg_pool2d(batch.right, {1 << s, 1 << s}, {1 << s, 1 << s});
    expected += 0.1 / (1 << s) * (SmoothnessLoss(d.left[s], l) + SmoothnessLoss(d.right[s], r)).item<double>();
  }
  EXPECT_NEAR(TotalLoss(d, batch, options, smooth_only).total.item<double>(), expected, 1e-6);
  // Occlusion only: 0.01 * sum_s (mean|d_l| + mean|d_r|).
  double occ = 0;
  for (int s = 0; s < 4; ++s) occ += 0.01 * (d.left[s].abs().mean() + d.right[s].abs().mean()).item<double>();
  const LossTerms occ_terms = TotalLoss(d, batch, options, LossSwitches{false, false, false, false, true});
  EXPECT_NEAR(occ_terms.total.item<double>(), occ, 1e-7);
  EXPECT_NEAR(occ_terms.occ, occ, 1e-7);
  // All terms: the total is the sum of the reported weighted terms.
  const LossTerms all = TotalLoss(d, batch, options, LossSwitches{});
  EXPECT_NEAR(all.total.item<double>(), all.unsupervised + all.supervised + all.lr + all.smooth + all.occ, 1e-5);
  EXPECT_GT(all.supervised, 0);
  EXPECT_GT(all.unsupervised, 0);
}

TEST(PostProcess, BordersComeFromOnePassAndTheMiddleIsTheMean) {
  const torch::Tensor direct = torch::ones({1, 1, 2, 40});
  const torch::Tensor mirrored = torch::full({1, 1, 2, 40}, 3.0);
  const torch::Tensor blended = BlendPostProcess(direct, mirrored);
  EXPECT_NEAR(blended[0][0][0][0].item<double>(), 3.0, 1e-6);   // left border: mirrored pass
  EXPECT_NEAR(blended[0][0][1][39].item<double>(), 1.0, 1e-6);  // right border: direct pass
  EXPECT_NEAR(blended[0][0][0][20].item<double>(), 2.0, 1e-6);  // middle: mean
}

}  // namespace
}  // namespace dvso::stacknet
