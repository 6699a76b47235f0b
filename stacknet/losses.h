// The loss of paper section 3.2, one function per term (eq. 2-6) plus their
// weighted sum over scales (eq. 1). Left terms are written out; right terms are
// the same functions with left and right swapped (and the warp direction
// flipped). Disparities are fractions of the image width (see warping.h).
#pragma once

#include <torch/torch.h>

#include "stacknet/networks.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// Single-scale SSIM with a 3x3 box filter (valid region, (H-2) x (W-2)),
// C1 = 0.01^2, C2 = 0.03^2, per channel.
torch::Tensor SsimMap(const torch::Tensor& x, const torch::Tensor& y);

// Eq. (2): mean of alpha * clamp((1 - SSIM) / 2, 0, 1) over the SSIM map plus
// (1 - alpha) * mean |I - I_recons| (monodepth's reading of the 1/N sums).
torch::Tensor PhotometricLoss(const torch::Tensor& image, const torch::Tensor& reconstruction, double alpha);

// berHu norm (Laina et al.): |r| if |r| <= c, else (r^2 + c^2) / (2c).
torch::Tensor BerHu(const torch::Tensor& residual, const torch::Tensor& threshold);

// Eq. (3): mean berHu of (prediction - label) over labelled pixels (mask > 0),
// threshold = fraction * max |residual| over the batch's labelled pixels.
// prediction, label, mask: N x 1 x H x W at the same resolution. 0 when no labels.
// relative = true (not the paper's): each residual is taken relative to its label and
// multiplied by the batch's mean label, r_i * mean(label) / label_i: the loss keeps
// its magnitude, but a 10 % error weighs as much at 2 px as at 40 px (a disparity error
// of x % is a depth error of ~x %, what the odometry inherits).
torch::Tensor SupervisedLoss(const torch::Tensor& prediction, const torch::Tensor& label, const torch::Tensor& mask,
                             double threshold_fraction, bool relative = false);

// Eq. (4), left: mean |d_l(x) - d_r(x - d_l(x))|. For the right term pass
// (d_r, d_l, +1): mean |d_r(x) - d_l(x + d_r(x))|.
torch::Tensor LeftRightConsistencyLoss(const torch::Tensor& disparity, const torch::Tensor& other_disparity,
                                       double direction = -1.0);

// Eq. (5): mean |d_xx| exp(-mean_c |I_xx|) + mean |d_yy| exp(-mean_c |I_yy|),
// second-order central differences over the valid interior.
torch::Tensor SmoothnessLoss(const torch::Tensor& disparity, const torch::Tensor& image);

// Eq. (6): mean |d|.
torch::Tensor OcclusionLoss(const torch::Tensor& disparity);

// Which terms a stage uses (paper 5.1 switches L_S / L_U off per stage).
struct LossSwitches {
  bool unsupervised = true;
  bool supervised = true;
  bool lr = true;
  bool smooth = true;
  bool occ = true;
};

// Network-resolution training batch. Images in [0, 1]; labels as fractions of
// the width with a mask (1 = labelled).
struct StereoBatch {
  torch::Tensor left, right;               // N x 3 x H x W
  torch::Tensor left_label, right_label;   // N x 1 x H x W
  torch::Tensor left_mask, right_mask;     // N x 1 x H x W
  StereoBatch to(const torch::Device& device) const;
};

// Weighted terms summed over scales (each already multiplied by its alpha).
struct LossTerms {
  torch::Tensor total;
  double unsupervised = 0, supervised = 0, lr = 0, smooth = 0, occ = 0;
};

// Eq. (1): sum over scales s of the weighted, left+right terms; alpha_smooth / 2^s.
LossTerms TotalLoss(const DisparityPyramid& disparities, const StereoBatch& batch, const LossOptions& options,
                    const LossSwitches& switches);

}  // namespace dvso::stacknet
