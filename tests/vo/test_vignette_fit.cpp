// vo/frame/vignette_fit.h on observations drawn from its own model: it finds the fall-off and the
// exposures, ignores outliers, and finds no fall-off where there is none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"
#include "vo/frame/vignette_fit.h"

namespace dvso::vo {
namespace {

struct SyntheticData {
  std::vector<VignetteObservation> observations;
  std::vector<double> gain, bias;
  int points = 0, frames = 0;
};

// Points of radiance 30-200 seen in 5 of `frames` frames each at random radii; frame exposures
// a in [0.7, 1.3] (a_0 = 1), b in [-8, 8]; Gaussian noise and a fraction of gross outliers.
SyntheticData MakeData(const RadialVignette& lens, double noise, double outlier_fraction, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gauss(0.0, noise);
  SyntheticData d;
  d.frames = 30;
  d.points = 3000;
  for (int f = 0; f < d.frames; ++f) {
    d.gain.push_back(f == 0 ? 1.0 : 0.7 + 0.6 * uniform(rng));
    d.bias.push_back(-8 + 16 * uniform(rng));
  }
  for (int p = 0; p < d.points; ++p) {
    const double radiance = 30 + 170 * uniform(rng);
    const int first = std::min(d.frames - 5, static_cast<int>(uniform(rng) * (d.frames - 4)));
    for (int f = first; f < first + 5; ++f) {
      const double rho_sq = 1.1 * uniform(rng);
      double intensity = d.gain[f] * lens.At(rho_sq) * radiance + d.bias[f] + gauss(rng);
      if (uniform(rng) < outlier_fraction) intensity += (uniform(rng) < 0.5 ? -1 : 1) * (30 + 60 * uniform(rng));
      d.observations.push_back({p, f, rho_sq, intensity});
    }
  }
  return d;
}

TEST(VignetteFit, FindsTheFallOffAndTheExposuresDespiteNoiseAndOutliers) {
  const RadialVignette lens{{-0.3, 0.05}};
  const SyntheticData d = MakeData(lens, /*noise=*/1.5, /*outlier_fraction=*/0.05, 11);
  const VignetteFit fit = FitVignette(d.observations, d.points, d.frames);
  ASSERT_EQ(fit.vignette.coefficients.size(), 2u);
  for (double rho_sq : {0.25, 0.5, 1.0}) EXPECT_NEAR(fit.vignette.At(rho_sq), lens.At(rho_sq), 0.005) << rho_sq;
  // Exposures are only loosely pinned: an offset of every radiance trades against the biases and gains
  // (exactly so where V = 1), so they are checked to a few percent and grey levels, V to half a percent.
  for (int f = 0; f < d.frames; ++f) {
    EXPECT_NEAR(fit.gain[f], d.gain[f], 0.03 * d.gain[f]) << f;
    EXPECT_NEAR(fit.bias[f], d.bias[f], 3.0) << f;
  }
  EXPECT_EQ(fit.points, d.points);
  EXPECT_EQ(fit.observations, static_cast<int>(d.observations.size()));
  EXPECT_LT(fit.rms, fit.rms_without_vignette);
  // The profile of the data follows the lens where it has samples.
  int bins_checked = 0;
  for (size_t i = 0; i < fit.profile_rho.size(); ++i) {
    if (std::isnan(fit.profile_ratio[i])) continue;
    EXPECT_NEAR(fit.profile_ratio[i], lens.At(fit.profile_rho[i] * fit.profile_rho[i]), 0.02) << fit.profile_rho[i];
    ++bins_checked;
  }
  EXPECT_GE(bins_checked, 18);
}

TEST(VignetteFit, FindsNoFallOffWhereThereIsNone) {
  const SyntheticData d = MakeData(RadialVignette{}, 1.5, 0.05, 12);
  const VignetteFit fit = FitVignette(d.observations, d.points, d.frames);
  EXPECT_NEAR(fit.vignette.At(1.0), 1.0, 0.005);
  EXPECT_NEAR(fit.vignette.At(0.5), 1.0, 0.005);
  EXPECT_NEAR(fit.rms, fit.rms_without_vignette, 0.01);
}

TEST(VignetteFit, LeavesOutPointsSeenTooRarelyAndRejectsBadInput) {
  SyntheticData d = MakeData(RadialVignette{{-0.2}}, 0.5, 0.0, 13);
  // One extra point seen twice only: not counted.
  d.observations.push_back({d.points, 0, 0.1, 100});
  d.observations.push_back({d.points, 1, 0.9, 80});
  const VignetteFit fit = FitVignette(d.observations, d.points + 1, d.frames);
  EXPECT_EQ(fit.points, d.points);
  EXPECT_EQ(fit.observations, static_cast<int>(d.observations.size()) - 2);
  EXPECT_NEAR(fit.vignette.At(1.0), 0.8, 0.005);

  // Three good observations of one point and a fourth out of range (frame, then point index): refused.
  const std::vector<VignetteObservation> good = {{0, 0, 0.1, 100}, {0, 1, 0.5, 90}, {0, 2, 0.9, 80}};
  EXPECT_NO_THROW(FitVignette(good, 1, 3));
  std::vector<VignetteObservation> bad_frame = good, bad_point = good;
  bad_frame.push_back({0, 3, 0.2, 95});
  bad_point.push_back({1, 0, 0.2, 95});
  EXPECT_THROW(FitVignette(bad_frame, 1, 3), Error);
  EXPECT_THROW(FitVignette(bad_point, 1, 3), Error);
  EXPECT_THROW(FitVignette({{0, 0, 0.1, 100}, {0, 1, 0.2, 90}}, 1, 2), Error);  // no point seen 3 times
  VignetteFitOptions bad;
  bad.num_coefficients = 7;
  EXPECT_THROW(FitVignette(d.observations, d.points + 1, d.frames, bad), Error);
}

}  // namespace
}  // namespace dvso::vo
