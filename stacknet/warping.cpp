#include "stacknet/warping.h"

namespace dvso::stacknet {

torch::Tensor WidthAsTensor(const torch::Tensor& map) {
  const torch::Tensor ones = torch::ones_like(map.narrow(1, 0, 1));
  return ones.sum(3, /*keepdim=*/true);
}

torch::Tensor WarpHorizontal(const torch::Tensor& source, const torch::Tensor& offset) {
  // Pixel coordinates from cumulative sums of ones: no sizes are baked into a trace.
  const torch::Tensor ones = torch::ones_like(offset);
  const torch::Tensor xs = ones.cumsum(3) - 1;  // 0 .. W-1
  const torch::Tensor ys = ones.cumsum(2) - 1;  // 0 .. H-1
  const torch::Tensor width = ones.sum(3, /*keepdim=*/true);
  const torch::Tensor height = ones.sum(2, /*keepdim=*/true);
  // align_corners = true: -1 and +1 are the centres of the first and last pixel.
  const torch::Tensor gx = 2 * (xs + offset * width) / (width - 1).clamp_min(1) - 1;
  const torch::Tensor gy = 2 * ys / (height - 1).clamp_min(1) - 1;
  const torch::Tensor grid = torch::stack({gx.squeeze(1), gy.squeeze(1)}, 3);  // N x H x W x 2
  return at::grid_sampler(source, grid, /*interpolation_mode=bilinear*/ 0, /*padding_mode=border*/ 1,
                          /*align_corners=*/true);
}

}  // namespace dvso::stacknet
