// Shared helpers of the StackNet tests: tiny network options and a synthetic
// stereo batch whose right view is the left one shifted by a known disparity.
#pragma once

#include <torch/torch.h>

#include "stacknet/losses.h"
#include "stacknet/options.h"

namespace dvso::stacknet::testing {

inline NetworkOptions TinyNetwork(int depth = 18) {
  NetworkOptions options;
  options.encoder_depth = depth;
  options.width_multiplier = 0.125;
  options.input_height = 32;
  options.input_width = 64;
  return options;
}

// Textured left image; right(x) = left(x + shift) so the true left disparity is
// `shift_pixels` everywhere; dense labels of that value on every 3rd pixel.
inline StereoBatch SyntheticBatch(int batch, int height, int width, double shift_pixels, uint64_t seed) {
  torch::manual_seed(seed);
  const torch::Tensor coarse = torch::rand({batch, 3, height / 4, width / 4});
  const torch::Tensor left = at::upsample_bilinear2d(coarse, {height, width}, false);
  StereoBatch b;
  b.left = left;
  // Shift by integer pixels: right(x) = left(x + s), edge replicated.
  const int s = static_cast<int>(shift_pixels);
  b.right = torch::cat({left.narrow(3, s, width - s), left.narrow(3, width - 1, 1).expand({batch, 3, height, s})}, 3);
  b.left_label = torch::full({batch, 1, height, width}, shift_pixels / width);
  b.right_label = b.left_label.clone();
  torch::Tensor mask = torch::zeros({batch, 1, height, width});
  mask.index_put_({torch::indexing::Slice(), torch::indexing::Slice(), torch::indexing::Slice(0, height, 3),
                   torch::indexing::Slice(0, width, 3)},
                  1.0);
  b.left_mask = mask;
  b.right_mask = mask.clone();
  return b;
}

}  // namespace dvso::stacknet::testing
