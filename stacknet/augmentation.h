// Training augmentation (paper 5.1, after monodepth): random gamma, brightness
// and per-channel colour shifts applied identically to both views, and a
// horizontal flip that swaps left and right (so the pair stays a valid
// left/right stereo pair, labels included).
#pragma once

#include <random>

#include "stacknet/dataset.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// Mirrors both views and swaps them: new left = flip(right), new right = flip(left).
StereoSample FlipAndSwap(const StereoSample& sample);

// Applies the configured random augmentation with `rng` (deterministic given its seed).
StereoSample Augment(const StereoSample& sample, const AugmentOptions& options, std::mt19937_64& rng);

}  // namespace dvso::stacknet
