// SimpleNet, ResidualNet and StackNet (paper section 3.1).
//  - SimpleNet: ResNet encoder + skip decoder, ELU, 4 scales of left and right
//    disparity = max_disparity * sigmoid (fraction of the width).
//  - ResidualNet: encoder with `residual_blocks` (12) residual blocks, leaky
//    ReLU, input [I_left, disp_simple_0^left, I_right_recons, I_left_recons, e_l],
//    additive residuals for all 4 scales, left and right.
//  - StackNet: disp_s = disp_simple_s (+) disp_res_s; SimpleNet can be frozen.
#pragma once

#include <torch/torch.h>

#include <vector>

#include "stacknet/layers.h"
#include "stacknet/options.h"
#include "stacknet/resnet_encoder.h"

namespace dvso::stacknet {

// Left and right disparity at scales s = 0..3 (resolution 1/2^s), each
// N x 1 x H/2^s x W/2^s, as a fraction of the image width.
struct DisparityPyramid {
  std::vector<torch::Tensor> left;
  std::vector<torch::Tensor> right;
  int num_scales() const { return static_cast<int>(left.size()); }
};

// Splits two-channel decoder maps into left (channel 0) / right (channel 1).
DisparityPyramid SplitLeftRight(const ScaleMaps& maps);

class SimpleNetImpl : public torch::nn::Module {
 public:
  explicit SimpleNetImpl(const NetworkOptions& options);
  // left_image: N x 3 x H x W in [0, 1].
  DisparityPyramid forward(const torch::Tensor& left_image);

 private:
  ResNetEncoder encoder{nullptr};
  SkipDecoder decoder{nullptr};
  bool standardize_input_ = false;  // with normalization "group": (I - 0.45) / 0.225 (the plain net keeps [0, 1])
};
TORCH_MODULE(SimpleNet);

// ResidualNet's 13 input channels in the order of paper 3.1: the one description of the layout, read by
// MakeResidualInputs (stacking order), ResidualNet's stem (count) and StandardizeResidualInputs (slices).
struct ResidualInputLayout {
  static constexpr int64_t kImageChannels = 3;  // RGB, as SimpleNet's input
  static constexpr int64_t kLeftImage = 0;                                            // I_left
  static constexpr int64_t kDisparity = kLeftImage + kImageChannels;                  // disp_simple_0^left (1)
  static constexpr int64_t kRightReconstruction = kDisparity + 1;                     // I_right_recons
  static constexpr int64_t kLeftReconstruction = kRightReconstruction + kImageChannels;  // I_left_recons
  static constexpr int64_t kError = kLeftReconstruction + kImageChannels;             // e_l
  static constexpr int64_t kChannels = kError + kImageChannels;                       // 13
};

// The 13-channel input of ResidualNet, exactly as listed in paper 3.1.
struct ResidualInputs {
  torch::Tensor right_reconstruction;  // I_right_recons = I_left warped with disp_simple_0^right
  torch::Tensor left_reconstruction;   // I_left_recons = I_right_recons back-warped with disp_simple_0^left
  torch::Tensor error;                 // e_l = |I_left - I_left_recons| (per channel)
  torch::Tensor stacked;               // [I_left, disp_0^left, I_right_recons, I_left_recons, e_l]
};
ResidualInputs MakeResidualInputs(const torch::Tensor& left_image, const torch::Tensor& simple_left_0,
                                  const torch::Tensor& simple_right_0);
// The stacked 13 channels on one scale (NetworkOptions::standardize_residual_inputs): the three images
// (I - 0.45) / 0.225, the disparity (fraction of the width) / 0.05, the reconstruction error / 0.1.
torch::Tensor StandardizeResidualInputs(const torch::Tensor& stacked);

class ResidualNetImpl : public torch::nn::Module {
 public:
  explicit ResidualNetImpl(const NetworkOptions& options);
  // Residuals (left, right) at 4 scales for the given ResidualNet input stack.
  DisparityPyramid forward(const torch::Tensor& stacked_inputs);

 private:
  double leaky_slope_;
  bool standardize_inputs_;
  torch::nn::Conv2d stem{nullptr};
  torch::nn::GroupNorm stem_norm{nullptr};  // with normalization "group"
  torch::nn::Sequential stage1{nullptr}, stage2{nullptr}, stage3{nullptr}, stage4{nullptr};
  SkipDecoder decoder{nullptr};
};
TORCH_MODULE(ResidualNet);

struct StackNetOutput {
  DisparityPyramid simple;  // SimpleNet's prediction
  DisparityPyramid refined; // disp_simple (+) disp_res
};

class StackNetImpl : public torch::nn::Module {
 public:
  explicit StackNetImpl(const NetworkOptions& options);
  StackNetOutput forward(const torch::Tensor& left_image);
  // Freezing SimpleNet (paper 5.1, second half of training): its parameters
  // stop requiring gradients and its outputs are detached.
  void SetSimpleNetFrozen(bool frozen);
  bool simple_net_frozen() const { return frozen_; }
  SimpleNet simple_net() const { return simple; }
  ResidualNet residual_net() const { return residual; }
  // The options it was built with: what its weights compute depends on some that are no parameters
  // (max_disparity, residual_leaky_slope, standardize_residual_inputs), which the export records.
  const NetworkOptions& network_options() const { return options_; }

 private:
  NetworkOptions options_;
  bool frozen_ = false;
  SimpleNet simple{nullptr};
  ResidualNet residual{nullptr};
};
TORCH_MODULE(StackNet);

}  // namespace dvso::stacknet
