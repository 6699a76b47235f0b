// Synthetic test scene for the frontend tests: the inside of a textured box
// (floor, ceiling, side walls, back wall) rendered by ray casting, so that
// every pixel has exact depth and any camera pose can be rendered.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/camera.h"

namespace dvso::vo::testing {

// Multi-scale blurred noise, values roughly in [20, 235].
inline cv::Mat MakeTexture(int size = 1024, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> n(0.f, 1.f);
  cv::Mat acc = cv::Mat::zeros(size, size, CV_32F);
  for (double sigma : {2.5, 6.0, 15.0}) {
    cv::Mat noise(size, size, CV_32F);
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) noise.at<float>(y, x) = n(rng);
    // Periodic blur: pad by wrapping, blur, crop (GaussianBlur has no BORDER_WRAP).
    const int pad = static_cast<int>(4 * sigma) + 1;
    cv::Mat padded, blurred_padded;
    cv::copyMakeBorder(noise, padded, pad, pad, pad, pad, cv::BORDER_WRAP);
    cv::GaussianBlur(padded, blurred_padded, cv::Size(0, 0), sigma, sigma);
    const cv::Mat blurred = blurred_padded(cv::Rect(pad, pad, size, size)).clone();
    cv::Scalar mean, stddev;
    cv::meanStdDev(blurred, mean, stddev);
    acc += (blurred - mean[0]) / stddev[0];
  }
  cv::Scalar mean, stddev;
  cv::meanStdDev(acc, mean, stddev);
  cv::Mat out = (acc - mean[0]) / stddev[0] * 40.0 + 128.0;
  cv::min(out, 235.0, out);
  cv::max(out, 20.0, out);
  return out;
}

inline float SampleWrapped(const cv::Mat& tex, double s, double t) {
  const int n = tex.cols;
  s = s - std::floor(s / n) * n;
  t = t - std::floor(t / n) * n;
  const int x0 = static_cast<int>(s), y0 = static_cast<int>(t);
  const int x1 = (x0 + 1) % n, y1 = (y0 + 1) % n;
  const float fx = static_cast<float>(s - x0), fy = static_cast<float>(t - y0);
  return (1 - fy) * ((1 - fx) * tex.at<float>(y0, x0) + fx * tex.at<float>(y0, x1)) +
         fy * ((1 - fx) * tex.at<float>(y1, x0) + fx * tex.at<float>(y1, x1));
}

struct BoxScene {
  double half_width = 4.0;   // side walls at x = +-half_width
  double floor_y = 1.6;      // floor (camera y points down)
  double ceiling_y = -2.4;
  double back_z = 14.0;
  double texels_per_metre = 20.0;  // keeps far walls free of aliasing
  cv::Mat texture = MakeTexture();

  // Renders intensity (CV_32F) and depth (CV_32F, z in the camera) for the
  // camera pose T_world_cam. Brightness: out = gain * I + bias.
  void Render(const PinholeCamera& cam, const Eigen::Isometry3d& T_world_cam, cv::Mat* image, cv::Mat* depth,
              double gain = 1.0, double bias = 0.0) const {
    *image = cv::Mat(cam.height, cam.width, CV_32F);
    if (depth) *depth = cv::Mat(cam.height, cam.width, CV_32F);
    const Eigen::Matrix3d R = T_world_cam.linear();
    const Eigen::Vector3d o = T_world_cam.translation();
    for (int y = 0; y < cam.height; ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const Eigen::Vector3d ray_c = cam.Unproject(x, y);
        const Eigen::Vector3d d = R * ray_c;
        double best = std::numeric_limits<double>::infinity();
        double s = 0, t = 0;
        auto hit = [&](double lambda, double ss, double tt) {
          if (lambda > 1e-6 && lambda < best) {
            best = lambda;
            s = ss;
            t = tt;
          }
        };
        if (std::fabs(d.x()) > 1e-12) {
          for (double wall : {-half_width, half_width}) {
            const double l = (wall - o.x()) / d.x();
            const Eigen::Vector3d p = o + l * d;
            hit(l, p.z() + (wall > 0 ? 300 : 0), p.y());
          }
        }
        if (std::fabs(d.y()) > 1e-12) {
          for (double wall : {ceiling_y, floor_y}) {
            const double l = (wall - o.y()) / d.y();
            const Eigen::Vector3d p = o + l * d;
            hit(l, p.x(), p.z() + (wall > 0 ? 500 : 0));
          }
        }
        if (std::fabs(d.z()) > 1e-12) {
          const double l = (back_z - o.z()) / d.z();
          const Eigen::Vector3d p = o + l * d;
          hit(l, p.x() + 100, p.y() + 100);
        }
        const float v = SampleWrapped(texture, s * texels_per_metre, t * texels_per_metre);
        image->at<float>(y, x) = static_cast<float>(gain * v + bias);
        // ray_c has z = 1 in the camera, so lambda is the camera-frame depth.
        if (depth) depth->at<float>(y, x) = static_cast<float>(best);
      }
    }
  }
};

inline PinholeCamera TestCamera(int width = 320, int height = 240) {
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.8 * width;
  c.cx = 0.5 * width - 0.5;
  c.cy = 0.5 * height - 0.5;
  return c;
}

}  // namespace dvso::vo::testing
