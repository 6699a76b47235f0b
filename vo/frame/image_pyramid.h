// Image pyramid with gradients: the only view the odometry has of an image.
// Level 0 is the (photometrically corrected) input; level l+1 averages 2x2
// blocks of level l. Sizes are floor(w/2) x floor(h/2) per level, so any
// width works (KITTI's 1241 px included; no divisibility by 2^levels assumed).
//
// Pixel-centre convention: pixel (x, y) of level l+1 covers pixels 2x..2x+1,
// 2y..2y+1 of level l, whose centres average to (2x + 0.5, 2y + 0.5). Hence
// fx_{l+1} = fx_l / 2 and cx_{l+1} = (cx_l + 0.5) / 2 - 0.5 (see LevelCamera).
//
// Per pixel we store (I, dI/dx, dI/dy) packed in one Eigen::Vector3f (as DSO
// does) so that bilinear interpolation reads one contiguous cache line per row,
// plus the squared gradient norm used by the pixel selector and the gradient-
// dependent residual weights (DSO's w_p = c^2 / (c^2 + |grad I|^2)).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.h"
#include "vo/frame/photometric_calibration.h"

namespace dvso::vo {

struct ImagePyramidOptions {
  int max_levels = 6;             // upper bound on the number of levels (DSO: PYR_LEVELS 6)
  int min_top_level_pixels = 5000;  // stop adding levels once a level has fewer pixels (DSO rule)
  int min_level_side = 12;        // never create a level narrower/shorter than this (pixels)
  void Check() const;
};

// One pyramid level. Row-major, stride == width.
struct PyramidLevel {
  int width = 0;
  int height = 0;
  PinholeCamera camera;                 // intrinsics of this level (width/height set)
  std::vector<Eigen::Vector3f> data;    // (intensity, d/dx, d/dy) per pixel
  std::vector<float> grad_sq;           // dx^2 + dy^2 per pixel

  const Eigen::Vector3f& At(int x, int y) const { return data[static_cast<size_t>(y) * width + x]; }
  float Intensity(int x, int y) const { return At(x, y)[0]; }
  float GradSq(int x, int y) const { return grad_sq[static_cast<size_t>(y) * width + x]; }

  // True when bilinear interpolation at (x, y) stays `border` pixels inside
  // (the gradients at the outermost pixel are one-sided, so use border >= 1).
  bool InBounds(float x, float y, float border = 1.5f) const {
    return x >= border && y >= border && x < width - 1 - border && y < height - 1 - border;
  }

  // Bilinear interpolation of (I, dI/dx, dI/dy) at sub-pixel (x, y).
  // Precondition: InBounds(x, y, 0) (callers check; no clamping here, it is
  // the innermost loop of tracking and bundle adjustment).
  Eigen::Vector3f Interpolate(float x, float y) const {
    const int ix = static_cast<int>(x);
    const int iy = static_cast<int>(y);
    const float dx = x - ix;
    const float dy = y - iy;
    const Eigen::Vector3f* p = data.data() + static_cast<size_t>(iy) * width + ix;
    return (1 - dy) * ((1 - dx) * p[0] + dx * p[1]) + dy * ((1 - dx) * p[width] + dx * p[width + 1]);
  }
  // Intensity only (cheaper).
  float InterpolateIntensity(float x, float y) const {
    const int ix = static_cast<int>(x);
    const int iy = static_cast<int>(y);
    const float dx = x - ix;
    const float dy = y - iy;
    const Eigen::Vector3f* p = data.data() + static_cast<size_t>(iy) * width + ix;
    return (1 - dy) * ((1 - dx) * p[0][0] + dx * p[1][0]) +
           dy * ((1 - dx) * p[width][0] + dx * p[width + 1][0]);
  }
};

class ImagePyramid {
 public:
  // Builds from a grey image: CV_8UC1 (raw camera values; `calibration`, may
  // be null, maps them to irradiance and removes vignetting) or CV_32FC1
  // (already corrected, e.g. rendered in tests; calibration ignored).
  // `exposure_ms` > 0 divides by the exposure time (DSO: B = G^-1(I) / (V t));
  // 0 means unknown (the affine brightness a, b absorbs it).
  ImagePyramid(const cv::Mat& image, const PinholeCamera& camera, const ImagePyramidOptions& options = {},
               const PhotometricCalibration* calibration = nullptr, double exposure_ms = 0.0);

  int num_levels() const { return static_cast<int>(levels_.size()); }
  const PyramidLevel& level(int l) const { return levels_[l]; }
  const PinholeCamera& camera(int l = 0) const { return levels_[l].camera; }
  int width(int l = 0) const { return levels_[l].width; }
  int height(int l = 0) const { return levels_[l].height; }
  double exposure_ms() const { return exposure_ms_; }

  // Intrinsics of the level below/above: exposed for tests and residual code.
  static PinholeCamera LevelCamera(const PinholeCamera& finer, int coarse_width, int coarse_height);

 private:
  void Build(const cv::Mat& level0_f32, const PinholeCamera& camera, const ImagePyramidOptions& options);

  std::vector<PyramidLevel> levels_;
  double exposure_ms_ = 0.0;
};

using ImagePyramidPtr = std::shared_ptr<const ImagePyramid>;

}  // namespace dvso::vo
