#include "stacknet/resnet_encoder.h"

#include "core/error.h"

namespace dvso::stacknet {

ResidualUnitImpl::ResidualUnitImpl(int64_t in_channels, int64_t planes, int64_t stride, bool bottleneck,
                                   Activation activation, double leaky_slope, bool group_norm)
    : activation_(activation), leaky_slope_(leaky_slope), bottleneck_(bottleneck) {
  if (bottleneck_) {
    out_channels_ = planes * 4;
    conv1 = register_module("conv1", MakeConv(in_channels, planes, 1));
    conv2 = register_module("conv2", MakeConv(planes, planes, 3, stride));
    conv3 = register_module("conv3", MakeConv(planes, out_channels_, 1));
  } else {
    out_channels_ = planes;
    conv1 = register_module("conv1", MakeConv(in_channels, planes, 3, stride));
    conv2 = register_module("conv2", MakeConv(planes, planes, 3));
  }
  if (stride != 1 || in_channels != out_channels_) {
    // Stride 1 on every stride-th pixel (forward): the values of a strided 1x1 convolution, whose oneDNN
    // backward in LibTorch 1.13 corrupts the heap on channels-last input with fewer than 16 input channels
    // (ResidualNet's first stage at width 0.25; training runs channels-last on the CPU, ToConvolutionLayout).
    shortcut = register_module("shortcut", MakeConv(in_channels, out_channels_, 1, 1));
    shortcut_stride_ = stride;
  }
  if (group_norm) {
    norm1 = register_module("norm1", MakeGroupNorm(conv1->options.out_channels()));
    norm2 = register_module("norm2", MakeGroupNorm(conv2->options.out_channels()));
    if (conv3) norm3 = register_module("norm3", MakeGroupNorm(out_channels_));
    if (shortcut) norm_shortcut = register_module("norm_shortcut", MakeGroupNorm(out_channels_));
  }
}

torch::Tensor ResidualUnitImpl::forward(const torch::Tensor& x) {
  auto act = [&](const torch::Tensor& t) { return Activate(t, activation_, leaky_slope_); };
  auto norm = [](torch::nn::GroupNorm& n, const torch::Tensor& t) { return n ? n->forward(t) : t; };
  torch::Tensor y = act(norm(norm1, conv1->forward(x)));
  if (bottleneck_) {
    y = act(norm(norm2, conv2->forward(y)));
    y = norm(norm3, conv3->forward(y));
  } else {
    y = norm(norm2, conv2->forward(y));
  }
  torch::Tensor identity = x;
  if (shortcut) {
    const torch::Tensor sampled =
        shortcut_stride_ == 1 ? x
                              : x.slice(2, 0, c10::nullopt, shortcut_stride_).slice(3, 0, c10::nullopt, shortcut_stride_);
    identity = norm(norm_shortcut, shortcut->forward(sampled));
  }
  return act(y + identity);
}

ResNetEncoderImpl::ResNetEncoderImpl(int depth, double width_multiplier, int64_t input_channels, bool group_norm) {
  std::vector<int> blocks;
  bool bottleneck = false;
  if (depth == 18) {
    blocks = {2, 2, 2, 2};
  } else if (depth == 34) {
    blocks = {3, 4, 6, 3};
  } else if (depth == 50) {
    blocks = {3, 4, 6, 3};
    bottleneck = true;
  } else {
    throw Error("ResNet depth must be 18, 34 or 50, got " + std::to_string(depth));
  }
  const int64_t stem = ScaledChannels(64, width_multiplier);
  conv1 = register_module("conv1", MakeConv(input_channels, stem, 7, 2));
  if (group_norm) norm1 = register_module("norm1", MakeGroupNorm(stem));
  int64_t channels = stem;
  auto make_layer = [&](int index, int64_t planes, int64_t stride) {
    torch::nn::Sequential layer;
    for (int b = 0; b < blocks[index]; ++b) {
      ResidualUnit unit(channels, ScaledChannels(planes, width_multiplier), b == 0 ? stride : 1, bottleneck,
                        Activation::kElu, 0.0, group_norm);
      channels = unit->out_channels();
      layer->push_back(unit);
    }
    return layer;
  };
  // Max-pool after conv1 gives 1/4 before layer1 (stride 1), as in ResNet.
  layer1 = register_module("layer1", make_layer(0, 64, 1));
  const int64_t c1 = channels;
  layer2 = register_module("layer2", make_layer(1, 128, 2));
  const int64_t c2 = channels;
  layer3 = register_module("layer3", make_layer(2, 256, 2));
  const int64_t c3 = channels;
  layer4 = register_module("layer4", make_layer(3, 512, 2));
  skip_channels_ = {stem, c1, c2, c3};
  bottom_channels_ = channels;
}

EncoderFeatures ResNetEncoderImpl::forward(const torch::Tensor& x) {
  EncoderFeatures f;
  torch::Tensor stem_out = conv1->forward(x);
  if (norm1) stem_out = norm1->forward(stem_out);
  const torch::Tensor c1 = torch::elu(stem_out);                                // 1/2
  const torch::Tensor pooled = torch::max_pool2d(c1, {3, 3}, {2, 2}, {1, 1});   // 1/4
  const torch::Tensor l1 = layer1->forward(pooled);                             // 1/4
  const torch::Tensor l2 = layer2->forward(l1);                                 // 1/8
  const torch::Tensor l3 = layer3->forward(l2);                                 // 1/16
  f.bottom = layer4->forward(l3);                                               // 1/32
  f.skips = {c1, l1, l2, l3};
  return f;
}

}  // namespace dvso::stacknet
