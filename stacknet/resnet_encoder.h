// ResNet-18/34/50 encoder of SimpleNet (paper 3.1: ResNet-50), written with the
// C++ frontend and trained from scratch (no pretrained weights exist here).
// Optional GroupNorm after every convolution (NetworkOptions::normalization): no
// batch normalisation, so training and inference behave the same and the traced
// module has no mode-dependent state.
#pragma once

#include <torch/torch.h>

#include "stacknet/layers.h"

namespace dvso::stacknet {

// Residual unit: two 3x3 convs (basic, ResNet-18/34) or 1x1-3x3-1x1
// (bottleneck, ResNet-50, expansion 4), projection shortcut when the shape changes.
class ResidualUnitImpl : public torch::nn::Module {
 public:
  ResidualUnitImpl(int64_t in_channels, int64_t planes, int64_t stride, bool bottleneck, Activation activation,
                   double leaky_slope, bool group_norm = false);
  torch::Tensor forward(const torch::Tensor& x);
  int64_t out_channels() const { return out_channels_; }

 private:
  Activation activation_;
  double leaky_slope_;
  bool bottleneck_;
  int64_t out_channels_;
  torch::nn::Conv2d conv1{nullptr}, conv2{nullptr}, conv3{nullptr}, shortcut{nullptr};
  int64_t shortcut_stride_ = 1;  // the projection reads every shortcut_stride_-th pixel (see the constructor)
  // Present only with group_norm: one per convolution above.
  torch::nn::GroupNorm norm1{nullptr}, norm2{nullptr}, norm3{nullptr}, norm_shortcut{nullptr};
};
TORCH_MODULE(ResidualUnit);

class ResNetEncoderImpl : public torch::nn::Module {
 public:
  // depth: 18, 34 or 50; input_channels: 3 for SimpleNet; group_norm: GroupNorm after each conv.
  ResNetEncoderImpl(int depth, double width_multiplier, int64_t input_channels = 3, bool group_norm = false);
  EncoderFeatures forward(const torch::Tensor& x);
  // Channels of the skips [1/2, 1/4, 1/8, 1/16] and of the 1/32 bottleneck.
  const std::vector<int64_t>& skip_channels() const { return skip_channels_; }
  int64_t bottom_channels() const { return bottom_channels_; }

 private:
  torch::nn::Conv2d conv1{nullptr};
  torch::nn::GroupNorm norm1{nullptr};
  torch::nn::Sequential layer1{nullptr}, layer2{nullptr}, layer3{nullptr}, layer4{nullptr};
  std::vector<int64_t> skip_channels_;
  int64_t bottom_channels_ = 0;
};
TORCH_MODULE(ResNetEncoder);

}  // namespace dvso::stacknet
