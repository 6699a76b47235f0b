// Training augmentation (paper 5.1, after monodepth): random gamma, brightness
// and per-channel colour shifts applied identically to both views, and a
// horizontal flip that swaps left and right (so the pair stays a valid
// left/right stereo pair, labels included). Optionally (not in the paper) both
// views turn grey, as DVSO's input from a grey camera does.
#pragma once

#include <random>

#include "stacknet/dataset.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// Mirrors both views and swaps them: new left = flip(right), new right = flip(left).
StereoSample FlipAndSwap(const StereoSample& sample);

// 3 x H x W RGB -> 3 x H x W with the BT.601 luma (core/luma.h) in every channel: how the predictor
// presents a grey image to the network (grey replicated to 3 channels).
torch::Tensor ToGrey(const torch::Tensor& rgb);

// Applies the configured random augmentation with `rng` (deterministic given its seed).
StereoSample Augment(const StereoSample& sample, const AugmentOptions& options, std::mt19937_64& rng);

}  // namespace dvso::stacknet
