#include "stacknet/networks.h"

#include "stacknet/warping.h"

namespace dvso::stacknet {

namespace {
// Typical street-image statistics of intensities in [0, 1]: the from-scratch encoders' input scale.
constexpr double kImageMean = 0.45, kImageStd = 0.225;
// Typical magnitudes of ResidualNet's other channels: disparity as a fraction of the width (~32 px of 640),
// and the left-right reconstruction error |I - I_recons| in [0, 1].
constexpr double kResidualDisparityScale = 0.05, kResidualErrorScale = 0.1;
}  // namespace

DisparityPyramid SplitLeftRight(const ScaleMaps& maps) {
  DisparityPyramid pyramid;
  for (const auto& m : maps.maps) {
    pyramid.left.push_back(m.narrow(1, 0, 1));
    pyramid.right.push_back(m.narrow(1, 1, 1));
  }
  return pyramid;
}

SimpleNetImpl::SimpleNetImpl(const NetworkOptions& options) {
  const bool group_norm = options.normalization == "group";
  encoder = register_module("encoder", ResNetEncoder(options.encoder_depth, options.width_multiplier, 3, group_norm));
  decoder = register_module("decoder", SkipDecoder(encoder->skip_channels(), encoder->bottom_channels(),
                                                   options.width_multiplier, Activation::kElu, 0.0,
                                                   options.max_disparity));
  if (group_norm) InitConvolutionsHe(*this);
  if (options.initial_disparity > 0) decoder->StartHeadsAt(options.initial_disparity);
  standardize_input_ = group_norm;
}

DisparityPyramid SimpleNetImpl::forward(const torch::Tensor& left_image) {
  // Zero-mean, unit-scale input for the from-scratch encoder.
  const torch::Tensor input = standardize_input_ ? (left_image - kImageMean) / kImageStd : left_image;
  return SplitLeftRight(decoder->forward(encoder->forward(input)));
}

ResidualInputs MakeResidualInputs(const torch::Tensor& left_image, const torch::Tensor& simple_left_0,
                                  const torch::Tensor& simple_right_0) {
  ResidualInputs in;
  in.right_reconstruction = ReconstructRight(left_image, simple_right_0);
  in.left_reconstruction = ReconstructLeft(in.right_reconstruction, simple_left_0);
  in.error = (left_image - in.left_reconstruction).abs();
  using L = ResidualInputLayout;
  TORCH_CHECK(left_image.size(1) == L::kImageChannels && simple_left_0.size(1) == 1,
              "ResidualNet inputs: expected a ", L::kImageChannels, "-channel image and a 1-channel disparity");
  // Stacked in ResidualInputLayout's order.
  in.stacked = torch::cat({left_image, simple_left_0, in.right_reconstruction, in.left_reconstruction, in.error}, 1);
  return in;
}

torch::Tensor StandardizeResidualInputs(const torch::Tensor& stacked) {
  using L = ResidualInputLayout;
  TORCH_CHECK(stacked.size(1) == L::kChannels, "ResidualNet inputs: expected ", L::kChannels, " channels, got ",
              stacked.size(1));
  // The two reconstructions are adjacent, so one slice standardises both.
  static_assert(L::kLeftReconstruction == L::kRightReconstruction + L::kImageChannels, "layout changed");
  return torch::cat({(stacked.narrow(1, L::kLeftImage, L::kImageChannels) - kImageMean) / kImageStd,
                     stacked.narrow(1, L::kDisparity, 1) / kResidualDisparityScale,
                     (stacked.narrow(1, L::kRightReconstruction, 2 * L::kImageChannels) - kImageMean) / kImageStd,
                     stacked.narrow(1, L::kError, L::kImageChannels) / kResidualErrorScale},
                    1);
}

ResidualNetImpl::ResidualNetImpl(const NetworkOptions& options)
    : leaky_slope_(options.residual_leaky_slope), standardize_inputs_(options.standardize_residual_inputs) {
  const double w = options.width_multiplier;
  const int64_t stem_channels = ScaledChannels(32, w);
  const bool group_norm = options.normalization == "group";
  stem = register_module("stem", MakeConv(ResidualInputLayout::kChannels, stem_channels, 7, 2));
  if (group_norm) stem_norm = register_module("stem_norm", MakeGroupNorm(stem_channels));
  const int per_stage = options.residual_blocks / 4;  // paper: 12 blocks = 4 stages x 3
  int64_t channels = stem_channels;
  std::vector<int64_t> skip_channels{stem_channels};
  auto make_stage = [&](int64_t planes) {
    torch::nn::Sequential stage;
    for (int b = 0; b < per_stage; ++b) {
      ResidualUnit unit(channels, ScaledChannels(planes, w), b == 0 ? 2 : 1, /*bottleneck=*/false,
                        Activation::kLeakyRelu, leaky_slope_, group_norm);
      channels = unit->out_channels();
      stage->push_back(unit);
    }
    return stage;
  };
  stage1 = register_module("stage1", make_stage(64));   // 1/4
  skip_channels.push_back(channels);
  stage2 = register_module("stage2", make_stage(128));  // 1/8
  skip_channels.push_back(channels);
  stage3 = register_module("stage3", make_stage(256));  // 1/16
  skip_channels.push_back(channels);
  stage4 = register_module("stage4", make_stage(512));  // 1/32
  if (group_norm) {
    // The encoder only: the decoder's heads stay zero, so StackNet starts as SimpleNet.
    InitConvolutionsHe(*stem);
    for (auto* stage : {&stage1, &stage2, &stage3, &stage4}) InitConvolutionsHe(**stage);
  }
  decoder = register_module("decoder", SkipDecoder(skip_channels, channels, w, Activation::kLeakyRelu,
                                                   leaky_slope_, /*sigmoid_scale=*/0.0));
}

DisparityPyramid ResidualNetImpl::forward(const torch::Tensor& stacked_inputs) {
  EncoderFeatures f;
  torch::Tensor stem_out = stem->forward(standardize_inputs_ ? StandardizeResidualInputs(stacked_inputs) : stacked_inputs);
  if (stem_norm) stem_out = stem_norm->forward(stem_out);
  const torch::Tensor s0 = torch::leaky_relu(stem_out, leaky_slope_);
  const torch::Tensor s1 = stage1->forward(s0);
  const torch::Tensor s2 = stage2->forward(s1);
  const torch::Tensor s3 = stage3->forward(s2);
  f.bottom = stage4->forward(s3);
  f.skips = {s0, s1, s2, s3};
  return SplitLeftRight(decoder->forward(f));
}

StackNetImpl::StackNetImpl(const NetworkOptions& options) : options_(options) {
  simple = register_module("simple", SimpleNet(options));
  residual = register_module("residual", ResidualNet(options));
}

void StackNetImpl::SetSimpleNetFrozen(bool frozen) {
  frozen_ = frozen;
  for (auto& p : simple->parameters()) p.set_requires_grad(!frozen);
}

StackNetOutput StackNetImpl::forward(const torch::Tensor& left_image) {
  StackNetOutput out;
  out.simple = simple->forward(left_image);
  if (frozen_) {
    for (auto& t : out.simple.left) t = t.detach();
    for (auto& t : out.simple.right) t = t.detach();
  }
  const ResidualInputs inputs = MakeResidualInputs(left_image, out.simple.left[0], out.simple.right[0]);
  // The residual network's input in the image's memory layout (channels-last on the CPU: see ToConvolutionLayout).
  const DisparityPyramid residuals = residual->forward(inputs.stacked.contiguous(left_image.suggest_memory_format()));
  for (int s = 0; s < out.simple.num_scales(); ++s) {
    out.refined.left.push_back(out.simple.left[s] + residuals.left[s]);
    out.refined.right.push_back(out.simple.right[s] + residuals.right[s]);
  }
  return out;
}

}  // namespace dvso::stacknet
