// Godard et al.'s post-processing (monodepth, paper 5.1): predict on the image
// and on its mirror, mirror the second prediction back, and blend: the left
// ~5 % of the columns come from the mirrored pass, the right ~5 % from the
// direct pass (those borders suffer from stereo disocclusion in one of the
// two), the rest is the mean of both.
#pragma once

#include <torch/torch.h>

namespace dvso::stacknet {

// direct, mirrored_back: N x 1 x H x W left disparities of the image and of
// the flipped image flipped back. Returns the blended map.
torch::Tensor BlendPostProcess(const torch::Tensor& direct, const torch::Tensor& mirrored_back);

}  // namespace dvso::stacknet
