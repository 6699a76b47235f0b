// Shapes of SimpleNet / ResidualNet / StackNet at every scale, ResidualNet's
// input as defined in paper 3.1, and the stage-2 freezing of SimpleNet.
#include <gtest/gtest.h>

#include "core/error.h"
#include "stacknet/device.h"
#include "stacknet/layers.h"
#include "stacknet/networks.h"
#include "stacknet/resnet_encoder.h"
#include "stacknet/trainer.h"
#include "stacknet_test_util.h"

namespace dvso::stacknet {
namespace {

void ExpectPyramidShapes(const DisparityPyramid& d, int64_t n, int64_t h, int64_t w) {
  ASSERT_EQ(d.num_scales(), 4);
  for (int s = 0; s < 4; ++s) {
    EXPECT_EQ(d.left[s].sizes(), (std::vector<int64_t>{n, 1, h >> s, w >> s})) << "scale " << s;
    EXPECT_EQ(d.right[s].sizes(), (std::vector<int64_t>{n, 1, h >> s, w >> s})) << "scale " << s;
  }
}

class EncoderDepths : public ::testing::TestWithParam<int> {};

TEST_P(EncoderDepths, SimpleNetGivesFourScalesOfBoundedLeftAndRightDisparity) {
  torch::manual_seed(0);
  const NetworkOptions options = testing::TinyNetwork(GetParam());
  SimpleNet net(options);
  const DisparityPyramid d = net->forward(torch::rand({2, 3, 32, 64}));
  ExpectPyramidShapes(d, 2, 32, 64);
  for (int s = 0; s < 4; ++s) {
    EXPECT_GT(d.left[s].min().item<double>(), 0.0);
    EXPECT_LT(d.left[s].max().item<double>(), options.max_disparity);  // max * sigmoid
  }
}
INSTANTIATE_TEST_SUITE_P(ResNet, EncoderDepths, ::testing::Values(18, 34, 50));

TEST(Networks, OtherInputSizesAndWidthMultipliersWork) {
  NetworkOptions options = testing::TinyNetwork();
  options.width_multiplier = 0.25;
  StackNet net(options);
  const StackNetOutput out = net->forward(torch::rand({1, 3, 64, 96}));
  ExpectPyramidShapes(out.simple, 1, 64, 96);
  ExpectPyramidShapes(out.refined, 1, 64, 96);
}

TEST(Networks, ResidualInputsFollowThePaper) {
  // Constant disparities of 1 px on a 8-wide ramp image: I_right_recons(x) = I(x + 1),
  // I_left_recons(x) = I_right_recons(x - 1) = I(x) away from the borders.
  const torch::Tensor image = torch::arange(8, torch::kFloat32).view({1, 1, 1, 8}).expand({1, 3, 2, 8}).contiguous();
  const torch::Tensor d = torch::full({1, 1, 2, 8}, 1.0 / 8);
  const ResidualInputs in = MakeResidualInputs(image, d, d);
  EXPECT_EQ(in.stacked.size(1), 13);  // 3 + 1 + 3 + 3 + 3 channels
  EXPECT_NEAR(in.right_reconstruction[0][0][0][3].item<double>(), 4.0, 1e-4);
  EXPECT_NEAR(in.left_reconstruction[0][0][0][3].item<double>(), 3.0, 1e-4);
  EXPECT_NEAR(in.error[0][0][0][3].item<double>(), 0.0, 1e-4);
  // Left border: recons(0) = right_recons(-1) -> border-clamped to right_recons(0) = I(1).
  EXPECT_NEAR(in.error[0][0][0][0].item<double>(), 1.0, 1e-4);
  // Channel 3 is disp_simple_0^left.
  EXPECT_TRUE(torch::equal(in.stacked.narrow(1, 3, 1), d));
  // The layout constants name the same slices as the stacking order.
  using L = ResidualInputLayout;
  EXPECT_EQ(L::kChannels, 13);
  EXPECT_TRUE(torch::equal(in.stacked.narrow(1, L::kLeftImage, 3), image));
  EXPECT_TRUE(torch::equal(in.stacked.narrow(1, L::kDisparity, 1), d));
  EXPECT_TRUE(torch::equal(in.stacked.narrow(1, L::kRightReconstruction, 3), in.right_reconstruction));
  EXPECT_TRUE(torch::equal(in.stacked.narrow(1, L::kLeftReconstruction, 3), in.left_reconstruction));
  EXPECT_TRUE(torch::equal(in.stacked.narrow(1, L::kError, 3), in.error));
}

TEST(Networks, ResidualInputsRejectAWrongChannelCount) {
  EXPECT_THROW(StandardizeResidualInputs(torch::zeros({1, 12, 2, 2})), c10::Error);
  EXPECT_THROW(MakeResidualInputs(torch::zeros({1, 1, 2, 8}), torch::zeros({1, 1, 2, 8}), torch::zeros({1, 1, 2, 8})),
               c10::Error);
}

TEST(Networks, StandardizedResidualInputsFollowTheHandFormula) {
  const torch::Tensor stacked = torch::arange(1, 14, torch::kFloat).mul(0.1).view({1, 13, 1, 1});
  const torch::Tensor out = StandardizeResidualInputs(stacked).flatten();
  ASSERT_EQ(out.size(0), 13);
  for (int c = 0; c < 13; ++c) {
    const double v = 0.1 * (c + 1);
    double expected = (v - 0.45) / 0.225;  // the three images
    if (c == 3) expected = v / 0.05;        // disparity
    if (c >= 10) expected = v / 0.1;        // reconstruction error
    EXPECT_NEAR(out[c].item<double>(), expected, 1e-5) << "channel " << c;
  }
}

TEST(Networks, ResidualNetStandardizesItsInputsOnlyWhenAsked) {
  NetworkOptions raw_options = testing::TinyNetwork();
  NetworkOptions standardized_options = raw_options;
  standardized_options.standardize_residual_inputs = true;
  ResidualNet raw(raw_options), standardized(standardized_options);
  {
    torch::NoGradGuard no_grad;
    torch::manual_seed(3);
    auto raw_params = raw->parameters(), standardized_params = standardized->parameters();
    ASSERT_EQ(raw_params.size(), standardized_params.size());
    for (size_t i = 0; i < raw_params.size(); ++i) {
      raw_params[i].uniform_(-0.2, 0.2);  // also the zero-initialised heads, so the outputs differ from 0
      standardized_params[i].copy_(raw_params[i]);
    }
  }
  const torch::Tensor x = torch::rand({1, 13, 32, 64}) * 0.5;
  const torch::Tensor expected = raw->forward(StandardizeResidualInputs(x)).left[0];
  EXPECT_TRUE(torch::allclose(standardized->forward(x).left[0], expected, 1e-4, 1e-5));
  EXPECT_FALSE(torch::allclose(raw->forward(x).left[0], expected, 1e-3, 1e-4));
}

TEST(Networks, ResidualNetHasTwelveResidualBlocksAndStartsAtZero) {
  torch::manual_seed(1);
  const NetworkOptions options = testing::TinyNetwork();
  StackNet net(options);
  int blocks = 0;
  for (const auto& child : net->residual_net()->named_modules()) {
    if (dynamic_cast<const ResidualUnitImpl*>(child.value().get())) ++blocks;
  }
  EXPECT_EQ(blocks, 12);
  // Zero-initialised residual heads: StackNet starts exactly at SimpleNet.
  const StackNetOutput out = net->forward(torch::rand({1, 3, 32, 64}));
  for (int s = 0; s < 4; ++s) EXPECT_TRUE(torch::equal(out.simple.left[s], out.refined.left[s]));
}

TEST(Networks, StageTwoTrainsResidualNetAndLeavesSimpleNetBitIdentical) {
  torch::manual_seed(2);
  StackNet net(testing::TinyNetwork());
  StageOptions stage;
  stage.model = "stack";
  stage.learning_rate = 1e-3;
  torch::optim::Adam optimizer(PrepareStage(net, stage), torch::optim::AdamOptions(stage.learning_rate));
  std::vector<torch::Tensor> simple_before, residual_before;
  for (const auto& p : net->simple_net()->parameters()) simple_before.push_back(p.detach().clone());
  for (const auto& p : net->residual_net()->parameters()) residual_before.push_back(p.detach().clone());
  const StereoBatch batch = testing::SyntheticBatch(2, 32, 64, 4, 7);
  for (int step = 0; step < 3; ++step) TrainStep(net, optimizer, stage, LossOptions{}, batch);
  const auto simple_after = net->simple_net()->parameters();
  for (size_t i = 0; i < simple_after.size(); ++i) {
    EXPECT_TRUE(torch::equal(simple_after[i], simple_before[i])) << "SimpleNet parameter " << i << " changed";
    EXPECT_FALSE(simple_after[i].grad().defined() && simple_after[i].grad().abs().sum().item<double>() > 0);
  }
  // Gradients reached every ResidualNet parameter, down to the first layer (stem).
  const auto residual_after = net->residual_net()->named_parameters();
  int changed = 0;
  for (size_t i = 0; i < residual_after.size(); ++i) {
    if (!torch::equal(residual_after[i].value(), residual_before[i])) ++changed;
  }
  EXPECT_EQ(changed, static_cast<int>(residual_after.size()));
  EXPECT_GT(net->residual_net()->named_parameters()["stem.weight"].grad().abs().sum().item<double>(), 0.0);
}

// The projection shortcut reads every 2nd pixel and convolves with stride 1 (a workaround for LibTorch 1.13's
// strided 1x1 backward, resnet_encoder.cpp): the same values as the strided 1x1 convolution it replaces.
TEST(Networks, ProjectionShortcutEqualsAStridedOneByOneConvolution) {
  torch::manual_seed(4);
  for (const int64_t size : {16, 17}) {  // odd sizes too: both give ceil(size / 2) rows and columns
    ResidualUnit unit(8, 16, 2, /*bottleneck=*/false, Activation::kElu, 0.0, /*group_norm=*/false);
    const torch::Tensor x = torch::randn({2, 8, size, size + 6});
    auto p = unit->named_parameters();
    const torch::Tensor main_path = torch::conv2d(
        torch::elu(torch::conv2d(x, p["conv1.weight"], p["conv1.bias"], 2, 1)), p["conv2.weight"], p["conv2.bias"], 1, 1);
    const torch::Tensor projection = torch::conv2d(x, p["shortcut.weight"], p["shortcut.bias"], /*stride=*/2);
    const torch::Tensor expected = torch::elu(main_path + projection);
    const torch::Tensor got = unit->forward(x);
    ASSERT_EQ(got.sizes(), expected.sizes());
    EXPECT_TRUE(torch::allclose(got, expected, 1e-5, 1e-6)) << "size " << size;
  }
}

// Training feeds the network channels-last on the CPU (ToConvolutionLayout): loss and gradients as accurate as
// with NCHW input, for both stages. Both layouts run other kernels (other summation orders) than each other, so
// both are compared with a float64 reference. Width 0.25 gives ResidualNet's first projection 8 input channels,
// where a strided 1x1 convolution's backward corrupted the heap in this layout (the test then aborts).
TEST(Networks, ChannelsLastTrainingGivesTheGradientsOfNchw) {
  NetworkOptions options = testing::TinyNetwork();
  options.width_multiplier = 0.25;
  options.input_height = 64;
  options.input_width = 192;
  const StereoBatch batch = testing::SyntheticBatch(2, 64, 192, 5, 11);
  enum Variant { kNchw, kChannelsLast, kFloat64Reference };
  for (const char* model : {"simple", "stack"}) {
    StageOptions stage;
    stage.model = model;
    std::vector<std::vector<torch::Tensor>> gradients;  // per variant, per trained parameter (float64)
    std::vector<double> losses;
    std::vector<std::string> names;
    for (const Variant variant : {kNchw, kChannelsLast, kFloat64Reference}) {
      torch::manual_seed(5);
      StackNet net(options);
      {
        // Both networks' heads start at zero weights, which would stop every gradient below them (0 == 0 tells
        // nothing): small random heads, the same in every variant.
        torch::NoGradGuard no_grad;
        for (auto& named : net->named_parameters()) {
          if (named.key().find("head") != std::string::npos && named.value().dim() == 4) {
            named.value().normal_(0.0, 0.05);
          }
        }
      }
      StereoBatch input = batch;
      if (variant == kFloat64Reference) {
        net->to(torch::kDouble);
        for (torch::Tensor* t : {&input.left, &input.right, &input.left_label, &input.right_label, &input.left_mask,
                                 &input.right_mask}) {
          *t = t->to(torch::kDouble);
        }
      }
      const std::vector<torch::Tensor> trained = PrepareStage(net, stage);
      names.clear();
      const auto named = std::string(model) == "simple" ? net->simple_net()->named_parameters()
                                                          : net->residual_net()->named_parameters();
      for (const auto& parameter : named) names.push_back(parameter.key());
      const torch::Tensor image = variant == kChannelsLast
                                      ? ToConvolutionLayout(input.left, torch::Device(torch::kCPU))
                                      : input.left.contiguous();
      ASSERT_EQ(image.is_contiguous(at::MemoryFormat::ChannelsLast), variant == kChannelsLast);
      const LossTerms terms = TotalLoss(StageForward(net, stage, image), input, LossOptions{}, SwitchesOf(stage));
      terms.total.backward();
      losses.push_back(terms.total.item<double>());
      gradients.emplace_back();
      for (const torch::Tensor& p : trained) gradients.back().push_back(p.grad().to(torch::kDouble));
    }
    ASSERT_EQ(names.size(), gradients[kNchw].size());
    EXPECT_NEAR(losses[kChannelsLast], losses[kFloat64Reference], 1e-5 * std::abs(losses[kFloat64Reference])) << model;
    EXPECT_NEAR(losses[kNchw], losses[kFloat64Reference], 1e-5 * std::abs(losses[kFloat64Reference])) << model;
    double largest = 0;
    for (const torch::Tensor& g : gradients[kFloat64Reference]) largest = std::max(largest, g.norm().item<double>());
    ASSERT_GT(largest, 0.0) << model;
    int compared = 0;
    for (size_t i = 0; i < names.size(); ++i) {
      const torch::Tensor& reference = gradients[kFloat64Reference][i];
      const double norm = reference.norm().item<double>();
      if (norm <= 1e-4 * largest) continue;  // zero up to rounding (a convolution bias right before a GroupNorm)
      ++compared;
      const double nchw_error = (gradients[kNchw][i] - reference).norm().item<double>() / norm;
      const double channels_last_error = (gradients[kChannelsLast][i] - reference).norm().item<double>() / norm;
      // float32 rounding (measured: SimpleNet stage NCHW ~1e-5, channels-last ~3e-4 relative; StackNet stage both
      // ~5e-3, its loss goes through the frozen SimpleNet's float32 outputs): channels-last within 2x NCHW's
      // error or 1 %. A layout bug (pixels or channels mixed up) would be of order 1. (0.2 % until session 40:
      // on an AVX-512 Sapphire Rapids CPU oneDNN's channels-last kernels round differently, 0.23 % against
      // NCHW's 0.06 % on one StackNet weight.)
      EXPECT_LE(channels_last_error, std::max(2.0 * nchw_error, 1e-2))
          << model << " " << names[i] << " (NCHW " << nchw_error << ")";
    }
    // Gradients reach most of the trained network in this test, not only the heads.
    EXPECT_GT(compared, static_cast<int>(names.size()) * 3 / 4) << model;
  }
}

TEST(Networks, GroupNormUsesTheLargestDivisorUpToEightGroups) {
  const std::vector<std::pair<int64_t, int64_t>> channels_groups{{3, 3}, {4, 4}, {8, 8}, {10, 5}, {12, 6}, {16, 8},
                                                                 {128, 8}};
  for (const auto& [channels, groups] : channels_groups) {
    EXPECT_EQ(MakeGroupNorm(channels)->options.num_groups(), groups) << channels << " channels";
  }
}

// Standard deviation of the 1/32 bottleneck of a freshly initialised ResNet-18 encoder.
double BottleneckStd(bool group_norm) {
  torch::manual_seed(3);
  ResNetEncoder encoder(18, 0.25, 3, group_norm);
  if (group_norm) InitConvolutionsHe(*encoder);
  torch::NoGradGuard no_grad;
  return encoder->forward(torch::randn({2, 3, 128, 256})).bottom.std().item<double>();
}

TEST(Networks, GroupNormKeepsTheEncoderSignalAliveAtInitialisation) {
  // The reason for normalization "group" (options.h): without it, LibTorch's default
  // initialisation shrinks the signal through the encoder's ~20 convolutions and the
  // bottleneck is nearly constant; with GroupNorm + He init it stays at unit scale.
  const double plain = BottleneckStd(false);
  const double normalised = BottleneckStd(true);
  EXPECT_GT(normalised, 0.3);
  EXPECT_LT(normalised, 3.0);
  EXPECT_LT(plain, 0.3 * normalised) << "plain " << plain << " normalised " << normalised;
}

TEST(Networks, NormalizationNoneBuildsThePlainEncoder) {
  NetworkOptions options = testing::TinyNetwork();
  auto count_norms = [](const torch::nn::Module& net) {
    int norms = 0;
    for (const auto& p : net.named_parameters()) norms += p.key().find("norm") != std::string::npos;
    return norms;
  };
  EXPECT_GT(count_norms(*StackNet(options)), 0);
  options.normalization = "none";
  EXPECT_EQ(count_norms(*StackNet(options)), 0);
  options.normalization = "batch";
  EXPECT_THROW(options.Check(), Error);
}

TEST(Networks, SimpleNetStartsAtTheInitialDisparity) {
  torch::manual_seed(4);
  NetworkOptions options = testing::TinyNetwork();
  options.initial_disparity = 0.03;
  SimpleNet net(options);
  torch::NoGradGuard no_grad;
  const DisparityPyramid d = net->forward(torch::rand({2, 3, 32, 64}));
  for (int s = 0; s < 4; ++s) {
    EXPECT_NEAR(d.left[s].min().item<double>(), 0.03, 1e-6) << "scale " << s;
    EXPECT_NEAR(d.right[s].max().item<double>(), 0.03, 1e-6) << "scale " << s;
  }
  options.initial_disparity = 0.4;  // above max_disparity (0.3)
  EXPECT_THROW(options.Check(), Error);
}

}  // namespace
}  // namespace dvso::stacknet
