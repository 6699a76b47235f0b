#include "stacknet/augmentation.h"

#include "core/luma.h"

namespace dvso::stacknet {

StereoSample FlipAndSwap(const StereoSample& s) {
  auto flip = [](const torch::Tensor& t) { return t.flip({2}); };
  StereoSample out;
  out.left = flip(s.right);
  out.right = flip(s.left);
  out.left_label = flip(s.right_label);
  out.right_label = flip(s.left_label);
  out.left_mask = flip(s.right_mask);
  out.right_mask = flip(s.left_mask);
  return out;
}

torch::Tensor ToGrey(const torch::Tensor& rgb) {
  const torch::Tensor weights =
      torch::tensor({kLumaWeightRed, kLumaWeightGreen, kLumaWeightBlue}, rgb.options()).view({3, 1, 1});
  return (rgb * weights).sum(0, /*keepdim=*/true).expand_as(rgb).contiguous();
}

StereoSample Augment(const StereoSample& sample, const AugmentOptions& options, std::mt19937_64& rng) {
  StereoSample out = sample;
  if (!options.enabled) return out;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };
  // Draw every random number unconditionally so the stream does not depend on branches.
  const bool flip = unit(rng) < options.flip_probability;
  const bool photometric = unit(rng) < options.probability;
  const double gamma = uniform(options.gamma_min, options.gamma_max);
  const double brightness = uniform(options.brightness_min, options.brightness_max);
  const float colors[3] = {static_cast<float>(uniform(options.color_min, options.color_max)),
                           static_cast<float>(uniform(options.color_min, options.color_max)),
                           static_cast<float>(uniform(options.color_min, options.color_max))};
  // Drawn only when grey augmentation is on, so configs without it keep their random stream (and old runs
  // stay reproducible).
  const bool grey = options.grey_probability > 0 && unit(rng) < options.grey_probability;
  if (flip) out = FlipAndSwap(out);
  if (photometric) {
    const torch::Tensor color = torch::from_blob(const_cast<float*>(colors), {3, 1, 1}, torch::kFloat32).clone();
    auto apply = [&](const torch::Tensor& image) {
      return (image.pow(gamma) * brightness * color).clamp(0, 1);
    };
    out.left = apply(out.left);
    out.right = apply(out.right);
  }
  if (grey) {
    out.left = ToGrey(out.left);
    out.right = ToGrey(out.right);
  }
  return out;
}

}  // namespace dvso::stacknet
