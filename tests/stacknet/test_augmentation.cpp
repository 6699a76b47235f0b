// Training augmentation: the grey option (BT.601 luma in every channel, both views, after the photometric
// changes), its range check and config key, and that leaving it off keeps the random stream of older configs.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "core/luma.h"
#include "stacknet/augmentation.h"
#include "stacknet/config.h"

namespace dvso::stacknet {
namespace {

StereoSample ColourPair() {
  torch::manual_seed(3);
  StereoSample sample;
  sample.left = torch::rand({3, 4, 5});
  sample.right = torch::rand({3, 4, 5});
  sample.left_label = torch::zeros({1, 4, 5});
  sample.right_label = torch::zeros({1, 4, 5});
  sample.left_mask = torch::zeros({1, 4, 5});
  sample.right_mask = torch::zeros({1, 4, 5});
  return sample;
}

AugmentOptions GreyOnly(double grey_probability) {
  AugmentOptions options;
  options.probability = 0;       // no photometric change
  options.flip_probability = 0;  // no flip
  options.grey_probability = grey_probability;
  return options;
}

TEST(Augmentation, GreyPutsTheLumaOfTheColourIntoEveryChannelOfBothViews) {
  const StereoSample sample = ColourPair();
  std::mt19937_64 rng(1);
  const StereoSample grey = Augment(sample, GreyOnly(1.0), rng);
  for (const auto& [in, out] : {std::pair{sample.left, grey.left}, std::pair{sample.right, grey.right}}) {
    ASSERT_EQ(out.sizes(), in.sizes());
    // By hand at one pixel: 0.299 R + 0.587 G + 0.114 B.
    const float r = in[0][2][3].item<float>(), g = in[1][2][3].item<float>(), b = in[2][2][3].item<float>();
    const float expected = 0.299f * r + 0.587f * g + 0.114f * b;
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(out[c][2][3].item<float>(), expected, 1e-6f) << "channel " << c;
    EXPECT_NEAR(Luma(r, g, b), expected, 1e-6f);
    EXPECT_TRUE(torch::allclose(out[0], out[1]) && torch::allclose(out[1], out[2]));
  }
  // Labels are untouched.
  EXPECT_TRUE(torch::equal(grey.left_label, sample.left_label));
}

TEST(Augmentation, GreyIsAppliedAtItsProbability) {
  const StereoSample sample = ColourPair();
  std::mt19937_64 rng(7);
  int grey = 0;
  const int draws = 400;
  for (int i = 0; i < draws; ++i) {
    const StereoSample out = Augment(sample, GreyOnly(0.25), rng);
    if (torch::allclose(out.left[0], out.left[1])) ++grey;
  }
  EXPECT_NEAR(grey / static_cast<double>(draws), 0.25, 0.06);
  std::mt19937_64 rng_off(7);
  EXPECT_TRUE(torch::equal(Augment(sample, GreyOnly(0.0), rng_off).left, sample.left));
}

TEST(Augmentation, GreyOffKeepsTheRandomStreamOfConfigsWithoutIt) {
  // A config without grey must consume exactly the seven draws it did before the option existed (flip,
  // photometric, gamma, brightness, three colour factors), so runs resumed or repeated from older configs
  // see the same augmentation.
  const StereoSample sample = ColourPair();
  AugmentOptions options;  // defaults: grey off
  std::mt19937_64 with_option(11), reference(11);
  Augment(sample, options, with_option);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 7; ++i) unit(reference);  // flip, photometric, gamma, brightness, 3 colour factors
  EXPECT_EQ(with_option(), reference());
  // With grey on, one more draw.
  options.grey_probability = 0.5;
  std::mt19937_64 grey_on(11), reference_on(11);
  Augment(sample, options, grey_on);
  for (int i = 0; i < 8; ++i) unit(reference_on);
  EXPECT_EQ(grey_on(), reference_on());
}

TEST(Augmentation, GreyProbabilityIsCheckedAndReadFromConfigs) {
  AugmentOptions options;
  options.grey_probability = 1.5;
  EXPECT_THROW(options.Check(), Error);
  options.grey_probability = -0.1;
  EXPECT_THROW(options.Check(), Error);
  const StackNetConfig config =
      ParseConfig("augment: {grey_probability: 0.3}\ndata: {sequences: [a]}\nstages: [{name: s}]\n", "x.yaml", false);
  EXPECT_DOUBLE_EQ(config.augment.grey_probability, 0.3);
  EXPECT_DOUBLE_EQ(ParseConfig(ConfigToYaml(config), "y.yaml", false).augment.grey_probability, 0.3);
}

}  // namespace
}  // namespace dvso::stacknet
