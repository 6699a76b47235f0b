#include "stacknet/post_process.h"

namespace dvso::stacknet {

torch::Tensor BlendPostProcess(const torch::Tensor& direct, const torch::Tensor& mirrored_back) {
  const int64_t width = direct.size(3);
  // Ramp l in [0, 1] over the columns; the mask is 1 at the left border and 0 beyond 10 % of the width.
  const torch::Tensor l = torch::linspace(0.0, 1.0, width, direct.options()).view({1, 1, 1, width});
  const torch::Tensor left_mask = 1.0 - (20.0 * (l - 0.05)).clamp(0.0, 1.0);
  const torch::Tensor right_mask = left_mask.flip({3});
  const torch::Tensor mean = 0.5 * (direct + mirrored_back);
  return right_mask * direct + left_mask * mirrored_back + (1.0 - left_mask - right_mask) * mean;
}

}  // namespace dvso::stacknet
