// Pixel selection with region-adaptive gradient thresholds (DSO's
// PixelSelector): the image is split into 32x32 regions whose threshold is the
// median gradient magnitude plus an offset, smoothed over neighbouring regions.
// Blocks of size pot x pot pick the pixel with the strongest gradient along a
// random direction above the threshold at level 0; blocks of 2 pot / 4 pot with
// no such pixel fall back to the (downweighted) thresholds of levels 1 / 2, so
// weakly textured areas still get points. pot adapts to reach the desired
// number of points.
#pragma once

#include <cstdint>
#include <vector>

#include "vo/frame/image_pyramid.h"

namespace dvso::vo {

struct PixelSelectorOptions {
  int desired_points = 2000;          // target number of points per keyframe (DSO setting_desiredPointDensity)
  int region_size = 32;               // side of the threshold regions in pixels (DSO: 32)
  double min_grad_hist_cut = 0.5;     // quantile of the region's gradient histogram (DSO setting_minGradHistCut)
  double min_grad_hist_add = 7.0;     // added to the quantile (DSO setting_minGradHistAdd)
  double grad_downweight_per_level = 0.75;  // threshold factor per coarser level (DSO setting_gradDownweightPerLevel)
  int border = 4;                     // pixels kept free at the image border (pattern + interpolation)
  int max_adapt_iterations = 3;       // passes adapting the block size to the desired count
  uint32_t seed = 42;                 // random directions: fixed seed = deterministic selection
  void Check() const;
};

struct SelectedPixel {
  int x = 0;           // level-0 pixel
  int y = 0;
  int level = 0;       // pyramid level whose gradient selected it (0, 1 or 2)
};

// Selects pixels in `pyramid` (level 0 coordinates). Deterministic.
// `block_size_hint` (optional, in/out): the block size that worked last time;
// consecutive keyframes look alike, so starting from it usually saves the
// adaptation passes (DSO keeps currentPotential across frames the same way).
std::vector<SelectedPixel> SelectPixels(const ImagePyramid& pyramid, const PixelSelectorOptions& options,
                                        double* block_size_hint = nullptr);

// Per-pixel squared threshold map at level 0 (exposed for tests).
std::vector<float> RegionThresholdsSq(const PyramidLevel& level, const PixelSelectorOptions& options, int* regions_x,
                                      int* regions_y);

}  // namespace dvso::vo
