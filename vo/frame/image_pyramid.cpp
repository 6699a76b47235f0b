#include "vo/frame/image_pyramid.h"

#include "core/error.h"

namespace dvso::vo {

void ImagePyramidOptions::Check() const {
  Require(max_levels >= 1 && max_levels <= 10, "pyramid max_levels must be in [1, 10]");
  Require(min_top_level_pixels >= 1, "pyramid min_top_level_pixels must be >= 1");
  Require(min_level_side >= 4, "pyramid min_level_side must be >= 4");
}

PinholeCamera ImagePyramid::LevelCamera(const PinholeCamera& finer, int coarse_width, int coarse_height) {
  PinholeCamera c = finer;
  c.fx = 0.5 * finer.fx;
  c.fy = 0.5 * finer.fy;
  c.cx = (finer.cx + 0.5) * 0.5 - 0.5;
  c.cy = (finer.cy + 0.5) * 0.5 - 0.5;
  c.width = coarse_width;
  c.height = coarse_height;
  return c;
}

namespace {

// Central differences inside, one-sided at the border, for the level's
// intensities stored in data[i][0].
void ComputeGradients(PyramidLevel* level) {
  const int w = level->width;
  const int h = level->height;
  auto& d = level->data;
  level->grad_sq.resize(d.size());
  for (int y = 0; y < h; ++y) {
    const int ym = y > 0 ? y - 1 : y;
    const int yp = y < h - 1 ? y + 1 : y;
    const float sy = (yp - ym) > 0 ? 1.0f / (yp - ym) : 0.0f;
    for (int x = 0; x < w; ++x) {
      const int xm = x > 0 ? x - 1 : x;
      const int xp = x < w - 1 ? x + 1 : x;
      const float sx = (xp - xm) > 0 ? 1.0f / (xp - xm) : 0.0f;
      const size_t i = static_cast<size_t>(y) * w + x;
      const float gx = sx * (d[static_cast<size_t>(y) * w + xp][0] - d[static_cast<size_t>(y) * w + xm][0]);
      const float gy = sy * (d[static_cast<size_t>(yp) * w + x][0] - d[static_cast<size_t>(ym) * w + x][0]);
      d[i][1] = gx;
      d[i][2] = gy;
      level->grad_sq[i] = gx * gx + gy * gy;
    }
  }
}

}  // namespace

ImagePyramid::ImagePyramid(const cv::Mat& image, const PinholeCamera& camera, const ImagePyramidOptions& options,
                           const PhotometricCalibration* calibration, double exposure_ms)
    : exposure_ms_(exposure_ms) {
  options.Check();
  Require(!image.empty(), "ImagePyramid: empty image");
  Require(image.channels() == 1, "ImagePyramid: expected a single-channel image");
  Require(image.cols == camera.width && image.rows == camera.height,
          "ImagePyramid: image size " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
              " differs from the camera's " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  cv::Mat level0;
  if (image.type() == CV_8UC1) {
    if (calibration != nullptr) {
      level0 = calibration->Correct(image);
    } else {
      image.convertTo(level0, CV_32F);
    }
  } else if (image.type() == CV_32FC1) {
    level0 = image;
  } else {
    throw Error("ImagePyramid: image must be CV_8UC1 or CV_32FC1");
  }
  if (exposure_ms > 0) level0 = level0 * static_cast<float>(1.0 / exposure_ms);
  Build(level0, camera, options);
}

void ImagePyramid::Build(const cv::Mat& level0_f32, const PinholeCamera& camera,
                         const ImagePyramidOptions& options) {
  levels_.clear();
  levels_.reserve(options.max_levels);
  PyramidLevel base;
  base.width = level0_f32.cols;
  base.height = level0_f32.rows;
  base.camera = camera;
  base.data.resize(static_cast<size_t>(base.width) * base.height);
  for (int y = 0; y < base.height; ++y) {
    const float* row = level0_f32.ptr<float>(y);
    for (int x = 0; x < base.width; ++x) base.data[static_cast<size_t>(y) * base.width + x] = {row[x], 0, 0};
  }
  ComputeGradients(&base);
  levels_.push_back(std::move(base));

  while (static_cast<int>(levels_.size()) < options.max_levels) {
    const PyramidLevel& fine = levels_.back();
    if (static_cast<long>(fine.width) * fine.height <= options.min_top_level_pixels) break;
    const int w = fine.width / 2;
    const int h = fine.height / 2;
    if (w < options.min_level_side || h < options.min_level_side) break;
    PyramidLevel coarse;
    coarse.width = w;
    coarse.height = h;
    coarse.camera = LevelCamera(fine.camera, w, h);
    coarse.data.resize(static_cast<size_t>(w) * h);
    for (int y = 0; y < h; ++y) {
      const Eigen::Vector3f* r0 = fine.data.data() + static_cast<size_t>(2 * y) * fine.width;
      const Eigen::Vector3f* r1 = r0 + fine.width;
      for (int x = 0; x < w; ++x) {
        const float v = 0.25f * (r0[2 * x][0] + r0[2 * x + 1][0] + r1[2 * x][0] + r1[2 * x + 1][0]);
        coarse.data[static_cast<size_t>(y) * w + x] = {v, 0, 0};
      }
    }
    ComputeGradients(&coarse);
    levels_.push_back(std::move(coarse));
  }
}

}  // namespace dvso::vo
