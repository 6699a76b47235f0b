#include "stacknet/losses.h"

#include <cmath>

#include "stacknet/layers.h"
#include "stacknet/warping.h"

namespace dvso::stacknet {

namespace {

// Mean over each valid 3x3 window (as avg_pool2d with kernel 3, stride 1, no padding), computed as two
// separable sums of shifted views: on the CPU this and its backward take a fraction of avg_pool2d's time,
// which was the largest single cost of the training loss (benchmarks/bench_torch_train_step).
torch::Tensor BoxMean3x3(const torch::Tensor& t) {
  const int64_t h = t.size(2), w = t.size(3);
  const torch::Tensor rows = t.narrow(3, 0, w - 2) + t.narrow(3, 1, w - 2) + t.narrow(3, 2, w - 2);
  return (rows.narrow(2, 0, h - 2) + rows.narrow(2, 1, h - 2) + rows.narrow(2, 2, h - 2)) * (1.0 / 9.0);
}

}  // namespace

torch::Tensor SsimMap(const torch::Tensor& x, const torch::Tensor& y) {
  constexpr double kC1 = 0.01 * 0.01;
  constexpr double kC2 = 0.03 * 0.03;
  TORCH_CHECK(x.size(2) >= 3 && x.size(3) >= 3, "SsimMap needs images of at least 3x3");
  const torch::Tensor mu_x = BoxMean3x3(x);
  const torch::Tensor mu_y = BoxMean3x3(y);
  const torch::Tensor sigma_x = BoxMean3x3(x * x) - mu_x * mu_x;
  const torch::Tensor sigma_y = BoxMean3x3(y * y) - mu_y * mu_y;
  const torch::Tensor sigma_xy = BoxMean3x3(x * y) - mu_x * mu_y;
  const torch::Tensor numerator = (2 * mu_x * mu_y + kC1) * (2 * sigma_xy + kC2);
  const torch::Tensor denominator = (mu_x * mu_x + mu_y * mu_y + kC1) * (sigma_x + sigma_y + kC2);
  return numerator / denominator;
}

torch::Tensor PhotometricLoss(const torch::Tensor& image, const torch::Tensor& reconstruction, double alpha) {
  const torch::Tensor ssim_term = ((1 - SsimMap(image, reconstruction)) / 2).clamp(0, 1).mean();
  const torch::Tensor l1_term = (image - reconstruction).abs().mean();
  return alpha * ssim_term + (1 - alpha) * l1_term;
}

torch::Tensor BerHu(const torch::Tensor& residual, const torch::Tensor& threshold) {
  const torch::Tensor a = residual.abs();
  // Guard c = 0 (all residuals zero): the quadratic branch is then never taken.
  const torch::Tensor c = threshold.clamp_min(1e-12);
  return torch::where(a <= c, a, (a * a + c * c) / (2 * c));
}

// Labels are width fractions; 1e-4 (0.06 px at 640) only guards a zero label.
constexpr double kMinRelativeLabel = 1e-4;

torch::Tensor SupervisedLoss(const torch::Tensor& prediction, const torch::Tensor& label, const torch::Tensor& mask,
                             double threshold_fraction, bool relative) {
  const torch::Tensor valid = mask > 0.5;
  const int64_t count = valid.sum().item<int64_t>();
  if (count == 0) return prediction.sum() * 0;  // keeps the graph; no labels in this batch
  const torch::Tensor labels = label.masked_select(valid);
  torch::Tensor residual = prediction.masked_select(valid) - labels;
  if (relative) residual = residual * (labels.mean() / labels.clamp_min(kMinRelativeLabel));
  // The threshold is a batch statistic, not a path for gradients (Laina et al.).
  const torch::Tensor threshold = threshold_fraction * residual.abs().max().detach();
  return BerHu(residual, threshold).sum() / static_cast<double>(count);
}

torch::Tensor LeftRightConsistencyLoss(const torch::Tensor& disparity, const torch::Tensor& other_disparity,
                                       double direction) {
  const torch::Tensor other_in_this_view = WarpHorizontal(other_disparity, direction * disparity);
  return (disparity - other_in_this_view).abs().mean();
}

torch::Tensor SmoothnessLoss(const torch::Tensor& disparity, const torch::Tensor& image) {
  const int64_t h = disparity.size(2), w = disparity.size(3);
  auto dxx = [](const torch::Tensor& t) {
    const int64_t n = t.size(3);
    return t.narrow(3, 2, n - 2) - 2 * t.narrow(3, 1, n - 2) + t.narrow(3, 0, n - 2);
  };
  auto dyy = [](const torch::Tensor& t) {
    const int64_t n = t.size(2);
    return t.narrow(2, 2, n - 2) - 2 * t.narrow(2, 1, n - 2) + t.narrow(2, 0, n - 2);
  };
  torch::Tensor loss = torch::zeros({}, disparity.options());
  if (w >= 3) {
    const torch::Tensor weight = torch::exp(-dxx(image).abs().mean(1, /*keepdim=*/true));
    loss = loss + (dxx(disparity).abs() * weight).mean();
  }
  if (h >= 3) {
    const torch::Tensor weight = torch::exp(-dyy(image).abs().mean(1, /*keepdim=*/true));
    loss = loss + (dyy(disparity).abs() * weight).mean();
  }
  return loss;
}

torch::Tensor OcclusionLoss(const torch::Tensor& disparity) { return disparity.abs().mean(); }

StereoBatch StereoBatch::to(const torch::Device& device) const {
  StereoBatch b;
  b.left = left.to(device);
  b.right = right.to(device);
  b.left_label = left_label.to(device);
  b.right_label = right_label.to(device);
  b.left_mask = left_mask.to(device);
  b.right_mask = right_mask.to(device);
  return b;
}

LossTerms TotalLoss(const DisparityPyramid& d, const StereoBatch& batch, const LossOptions& options,
                    const LossSwitches& on) {
  LossTerms terms;
  torch::Tensor total = torch::zeros({}, batch.left.options());
  const int scales = std::min(options.num_scales, d.num_scales());
  for (int s = 0; s < scales; ++s) {
    const int factor = 1 << s;
    const torch::Tensor left = Downsample(batch.left, factor);
    const torch::Tensor right = Downsample(batch.right, factor);
    const torch::Tensor& dl = d.left[s];
    const torch::Tensor& dr = d.right[s];
    if (on.unsupervised && options.alpha_u > 0) {
      const torch::Tensor t = options.alpha_u * (PhotometricLoss(left, ReconstructLeft(right, dl), options.ssim_alpha) +
                                                 PhotometricLoss(right, ReconstructRight(left, dr), options.ssim_alpha));
      total = total + t;
      terms.unsupervised += t.item<double>();
    }
    if (on.supervised && options.alpha_s > 0) {
      // Sparse labels live at the input resolution: compare the upsampled prediction there.
      const torch::Tensor dl_full = factor == 1 ? dl : UpsampleBilinear(dl, factor);
      const torch::Tensor dr_full = factor == 1 ? dr : UpsampleBilinear(dr, factor);
      const torch::Tensor t =
          options.alpha_s * (SupervisedLoss(dl_full, batch.left_label, batch.left_mask, options.berhu_fraction,
                                            options.relative_supervision) +
                             SupervisedLoss(dr_full, batch.right_label, batch.right_mask, options.berhu_fraction,
                                            options.relative_supervision));
      total = total + t;
      terms.supervised += t.item<double>();
    }
    if (on.lr && options.alpha_lr > 0) {
      const torch::Tensor t =
          options.alpha_lr * (LeftRightConsistencyLoss(dl, dr, -1.0) + LeftRightConsistencyLoss(dr, dl, +1.0));
      total = total + t;
      terms.lr += t.item<double>();
    }
    if (on.smooth && options.alpha_smooth > 0) {
      const double weight = options.alpha_smooth / std::pow(2.0, s);
      const torch::Tensor t = weight * (SmoothnessLoss(dl, left) + SmoothnessLoss(dr, right));
      total = total + t;
      terms.smooth += t.item<double>();
    }
    if (on.occ && options.alpha_occ > 0) {
      const torch::Tensor t = options.alpha_occ * (OcclusionLoss(dl) + OcclusionLoss(dr));
      total = total + t;
      terms.occ += t.item<double>();
    }
  }
  terms.total = total;
  return terms;
}

}  // namespace dvso::stacknet
