#include "stacknet/layers.h"

#include <algorithm>
#include <cmath>

namespace dvso::stacknet {

torch::Tensor Activate(const torch::Tensor& x, Activation activation, double leaky_slope) {
  if (activation == Activation::kElu) return torch::elu(x);
  return torch::leaky_relu(x, leaky_slope);
}

torch::Tensor UpsampleNearest(const torch::Tensor& x, double factor) {
  const std::vector<double> scales{factor, factor};
  return at::upsample_nearest2d(x, c10::nullopt, scales);
}

torch::Tensor UpsampleBilinear(const torch::Tensor& x, double factor) {
  const std::vector<double> scales{factor, factor};
  return at::upsample_bilinear2d(x, c10::nullopt, /*align_corners=*/false, scales);
}

torch::Tensor Downsample(const torch::Tensor& x, int factor) {
  if (factor == 1) return x;
  return torch::avg_pool2d(x, {factor, factor}, {factor, factor});
}

int64_t ScaledChannels(int64_t channels, double width_multiplier) {
  return std::max<int64_t>(1, static_cast<int64_t>(std::lround(channels * width_multiplier)));
}

torch::nn::Conv2d MakeConv(int64_t in, int64_t out, int64_t kernel, int64_t stride, bool bias) {
  return torch::nn::Conv2d(
      torch::nn::Conv2dOptions(in, out, kernel).stride(stride).padding(kernel / 2).bias(bias));
}

torch::nn::GroupNorm MakeGroupNorm(int64_t channels) {
  constexpr int64_t kMaxNormGroups = 8;
  int64_t groups = std::min(kMaxNormGroups, channels);
  while (channels % groups != 0) --groups;
  return torch::nn::GroupNorm(torch::nn::GroupNormOptions(groups, channels));
}

void InitConvolutionsHe(torch::nn::Module& module) {
  torch::NoGradGuard no_grad;
  auto init = [](torch::nn::Module& m) {
    if (auto* conv = m.as<torch::nn::Conv2dImpl>()) {
      torch::nn::init::kaiming_normal_(conv->weight, 0.0, torch::kFanOut, torch::kReLU);
      if (conv->bias.defined()) conv->bias.zero_();
    }
  };
  // modules(include_self = true) needs shared_from_this(), which a module under construction
  // does not have yet: visit the module itself, then its descendants.
  init(module);
  for (auto& child : module.modules(/*include_self=*/false)) init(*child);
}

SkipDecoderImpl::SkipDecoderImpl(const std::vector<int64_t>& skip_channels, int64_t bottom_channels,
                                 double width_multiplier, Activation activation, double leaky_slope,
                                 double sigmoid_scale)
    : activation_(activation), leaky_slope_(leaky_slope), sigmoid_scale_(sigmoid_scale) {
  TORCH_CHECK(skip_channels.size() == 4, "SkipDecoder needs 4 skip levels");
  auto c = [&](int64_t n) { return ScaledChannels(n, width_multiplier); };
  // Resize-convolutions (nearest x2 + 3x3 conv) and the 3x3 "iconv" that fuses the skip.
  upconv5 = register_module("upconv5", MakeConv(bottom_channels, c(256), 3));
  iconv5 = register_module("iconv5", MakeConv(c(256) + skip_channels[3], c(256), 3));
  upconv4 = register_module("upconv4", MakeConv(c(256), c(128), 3));
  iconv4 = register_module("iconv4", MakeConv(c(128) + skip_channels[2], c(128), 3));
  head3 = register_module("head3", MakeConv(c(128), 2, 3));
  upconv3 = register_module("upconv3", MakeConv(c(128), c(64), 3));
  iconv3 = register_module("iconv3", MakeConv(c(64) + skip_channels[1] + 2, c(64), 3));
  head2 = register_module("head2", MakeConv(c(64), 2, 3));
  upconv2 = register_module("upconv2", MakeConv(c(64), c(32), 3));
  iconv2 = register_module("iconv2", MakeConv(c(32) + skip_channels[0] + 2, c(32), 3));
  head1 = register_module("head1", MakeConv(c(32), 2, 3));
  upconv1 = register_module("upconv1", MakeConv(c(32), c(16), 3));
  iconv1 = register_module("iconv1", MakeConv(c(16) + 2, c(16), 3));
  head0 = register_module("head0", MakeConv(c(16), 2, 3));
  if (sigmoid_scale_ <= 0) {
    torch::NoGradGuard no_grad;
    for (auto* head : {&head3, &head2, &head1, &head0}) {
      (*head)->weight.zero_();
      (*head)->bias.zero_();
    }
  }
}

void SkipDecoderImpl::StartHeadsAt(double disparity) {
  TORCH_CHECK(sigmoid_scale_ > 0 && disparity > 0 && disparity < sigmoid_scale_,
              "StartHeadsAt needs sigmoid heads and 0 < disparity < their scale");
  const double p = disparity / sigmoid_scale_;
  const double logit = std::log(p / (1.0 - p));
  torch::NoGradGuard no_grad;
  for (auto* head : {&head3, &head2, &head1, &head0}) {
    (*head)->weight.zero_();  // flat start; the first step already gives the weights a gradient
    (*head)->bias.fill_(logit);
  }
}

torch::Tensor SkipDecoderImpl::Head(torch::nn::Conv2d& head, const torch::Tensor& x) const {
  torch::Tensor y = head->forward(x);
  if (sigmoid_scale_ > 0) y = sigmoid_scale_ * torch::sigmoid(y);
  return y;
}

ScaleMaps SkipDecoderImpl::forward(const EncoderFeatures& f) {
  const auto& skip = f.skips;
  torch::Tensor x = Act(upconv5->forward(UpsampleNearest(f.bottom)));          // 1/16
  x = Act(iconv5->forward(torch::cat({x, skip[3]}, 1)));
  x = Act(upconv4->forward(UpsampleNearest(x)));                               // 1/8
  x = Act(iconv4->forward(torch::cat({x, skip[2]}, 1)));
  torch::Tensor out3 = Head(head3, x);
  x = Act(upconv3->forward(UpsampleNearest(x)));                               // 1/4
  x = Act(iconv3->forward(torch::cat({x, skip[1], UpsampleBilinear(out3)}, 1)));
  torch::Tensor out2 = Head(head2, x);
  x = Act(upconv2->forward(UpsampleNearest(x)));                               // 1/2
  x = Act(iconv2->forward(torch::cat({x, skip[0], UpsampleBilinear(out2)}, 1)));
  torch::Tensor out1 = Head(head1, x);
  x = Act(upconv1->forward(UpsampleNearest(x)));                               // 1/1
  x = Act(iconv1->forward(torch::cat({x, UpsampleBilinear(out1)}, 1)));
  torch::Tensor out0 = Head(head0, x);
  return ScaleMaps{{out0, out1, out2, out3}};
}

}  // namespace dvso::stacknet
