// Building blocks shared by SimpleNet and ResidualNet: activations, resize-
// convolution (nearest x2 + conv, paper 3.1 / Odena et al.), and the skip
// decoder that turns encoder features into 4 scales of two-channel maps.
// All resampling uses scale factors, never fixed sizes, so that a traced
// TorchScript module generalises to other input sizes.
#pragma once

#include <torch/torch.h>

#include <vector>

namespace dvso::stacknet {

enum class Activation { kElu, kLeakyRelu };

// Applies the activation (ELU for SimpleNet, leaky ReLU for ResidualNet; paper 5.1).
torch::Tensor Activate(const torch::Tensor& x, Activation activation, double leaky_slope);

// Nearest / bilinear x`factor` upsampling by scale factor (shape-free when traced).
torch::Tensor UpsampleNearest(const torch::Tensor& x, double factor = 2.0);
torch::Tensor UpsampleBilinear(const torch::Tensor& x, double factor = 2.0);
// Average-pools by an integer factor (image pyramids of the loss).
torch::Tensor Downsample(const torch::Tensor& x, int factor);

// Channel count after the width multiplier (at least 1).
int64_t ScaledChannels(int64_t channels, double width_multiplier);

// "Same"-padded convolution.
torch::nn::Conv2d MakeConv(int64_t in, int64_t out, int64_t kernel, int64_t stride = 1, bool bias = true);

// GroupNorm over `channels` with the largest group count <= kMaxNormGroups that divides it
// (narrow CPU networks have 4..128 channels per layer).
torch::nn::GroupNorm MakeGroupNorm(int64_t channels);

// He (Kaiming) normal initialisation, fan-out, of every convolution in `module` (biases 0):
// variance-preserving for (leaky) ReLU / ELU networks trained from scratch. LibTorch's default
// (uniform, a = sqrt(5)) shrinks the activations by ~sqrt(3) per layer.
void InitConvolutionsHe(torch::nn::Module& module);

// Encoder output consumed by the decoder: skips at 1/2, 1/4, 1/8, 1/16 and the
// bottleneck at 1/32 of the input resolution.
struct EncoderFeatures {
  std::vector<torch::Tensor> skips;  // [1/2, 1/4, 1/8, 1/16]
  torch::Tensor bottom;              // 1/32
};

// Two-channel (left, right) maps at scales s = 0..3 (resolution 1/2^s).
struct ScaleMaps {
  std::vector<torch::Tensor> maps;  // maps[s]: N x 2 x H/2^s x W/2^s
};

// Decoder with skip connections and resize-convolution (monodepth / DispNet
// layout). Each output head is conv3x3 -> 2 channels; `sigmoid_scale` > 0
// gives max * sigmoid(x) (SimpleNet disparities), otherwise a linear head
// initialised to zero (ResidualNet residuals start at 0: StackNet starts as SimpleNet).
class SkipDecoderImpl : public torch::nn::Module {
 public:
  SkipDecoderImpl(const std::vector<int64_t>& skip_channels, int64_t bottom_channels, double width_multiplier,
                  Activation activation, double leaky_slope, double sigmoid_scale);
  ScaleMaps forward(const EncoderFeatures& features);
  // Sigmoid heads only: every head starts at `disparity` (fraction of the width) everywhere,
  // bias = logit(disparity / sigmoid_scale), weights 0. With the default
  // bias 0 the first output is sigmoid_scale / 2 (0.15 of the width, ~8x a street scene's
  // median disparity), and a 2000-step CPU run spends its steps moving that offset.
  void StartHeadsAt(double disparity);

 private:
  torch::Tensor Act(const torch::Tensor& x) const { return Activate(x, activation_, leaky_slope_); }
  torch::Tensor Head(torch::nn::Conv2d& head, const torch::Tensor& x) const;

  Activation activation_;
  double leaky_slope_;
  double sigmoid_scale_;
  torch::nn::Conv2d upconv5{nullptr}, iconv5{nullptr}, upconv4{nullptr}, iconv4{nullptr}, upconv3{nullptr},
      iconv3{nullptr}, upconv2{nullptr}, iconv2{nullptr}, upconv1{nullptr}, iconv1{nullptr};
  torch::nn::Conv2d head3{nullptr}, head2{nullptr}, head1{nullptr}, head0{nullptr};
};
TORCH_MODULE(SkipDecoder);

}  // namespace dvso::stacknet
