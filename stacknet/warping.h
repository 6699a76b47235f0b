// Differentiable horizontal warping of rectified stereo images by disparity
// (bilinear sampling, Jaderberg et al.; paper 3.1 / eq. 2 / eq. 4).
// Disparities are fractions of the image width (monodepth convention), so one
// map is valid at every scale; pixels = fraction * width.
#pragma once

#include <torch/torch.h>

namespace dvso::stacknet {

// output(x, y) = source(x + offset(x, y) * W, y), bilinear in x, border
// padding. source: N x C x H x W, offset: N x 1 x H x W (fraction of W).
// The sampling grid is built from the tensors' own shapes with tensor ops,
// so a traced module works for any input size.
torch::Tensor WarpHorizontal(const torch::Tensor& source, const torch::Tensor& offset);

// Reconstructs the left view from the right image: I_right(x - d_left(x)).
inline torch::Tensor ReconstructLeft(const torch::Tensor& right_image, const torch::Tensor& left_disparity) {
  return WarpHorizontal(right_image, -left_disparity);
}
// Reconstructs the right view from the left image: I_left(x + d_right(x)).
inline torch::Tensor ReconstructRight(const torch::Tensor& left_image, const torch::Tensor& right_disparity) {
  return WarpHorizontal(left_image, right_disparity);
}

// Width of a N x C x H x W tensor as a N x 1 x H x 1 tensor computed by tensor
// ops (traced shape-free); used to convert fractions to pixels in exports.
torch::Tensor WidthAsTensor(const torch::Tensor& map);

}  // namespace dvso::stacknet
