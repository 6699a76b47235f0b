// Synthetic data for the backend tests: images from closed-form functions and
// a small ray-cast scene of textured planes seen from known poses.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "core/camera.h"
#include "core/lie.h"
#include "vo/frame/image_pyramid.h"

namespace dvso::vo::testing {

inline PinholeCamera SmallCamera(int width = 320, int height = 240) {
  PinholeCamera c;
  c.fx = 300.0;
  c.fy = 300.0;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  c.width = width;
  c.height = height;
  return c;
}

inline cv::Mat ImageFromFunction(const PinholeCamera& camera, const std::function<float(double, double)>& f) {
  cv::Mat image(camera.height, camera.width, CV_32FC1);
  for (int y = 0; y < camera.height; ++y) {
    for (int x = 0; x < camera.width; ++x) image.at<float>(y, x) = f(x, y);
  }
  return image;
}

inline ImagePyramidPtr MakePyramid(const cv::Mat& image, const PinholeCamera& camera) {
  return std::make_shared<const ImagePyramid>(image, camera);
}

// Solid texture (a sum of sinusoids in world coordinates), 0..255 range.
inline double Texture(const Eigen::Vector3d& X) {
  return 128.0 + 38.0 * std::sin(3.1 * X.x() + 1.3 * X.y()) + 28.0 * std::sin(2.3 * X.y() - 1.7 * X.z() + 0.5) +
         24.0 * std::sin(4.1 * X.z() + 2.9 * X.x()) + 18.0 * std::sin(5.3 * X.x() - 4.7 * X.y() + 1.1) +
         12.0 * std::sin(7.9 * X.y() + 6.1 * X.x() + 0.3 * X.z());
}

// A "room" of planes n . X = d (world frame): back wall, floor, left wall.
struct PlaneScene {
  std::vector<Eigen::Vector4d> planes = {
      {0, 0, 1, 12.0},   // back wall z = 12
      {0, 1, 0, 2.0},    // floor y = 2 (y points down)
      {1, 0, 0, -5.0},   // left wall x = -5
  };

  // Depth (camera z) of the first surface hit by the ray through (u, v); +inf if none.
  double DepthAt(const Eigen::Isometry3d& world_to_camera, const PinholeCamera& camera, double u, double v,
                 Eigen::Vector3d* world_point = nullptr) const {
    const Eigen::Isometry3d camera_to_world = world_to_camera.inverse();
    const Eigen::Vector3d origin = camera_to_world.translation();
    const Eigen::Vector3d ray_cam = camera.Unproject(u, v);  // z = 1
    const Eigen::Vector3d dir = camera_to_world.linear() * ray_cam;
    double best = std::numeric_limits<double>::infinity();
    for (const Eigen::Vector4d& p : planes) {
      const double denom = p.head<3>().dot(dir);
      if (std::abs(denom) < 1e-12) continue;
      const double s = (p(3) - p.head<3>().dot(origin)) / denom;  // s = camera z since ray z = 1
      if (s > 0.1 && s < best) best = s;
    }
    if (world_point != nullptr && std::isfinite(best)) *world_point = origin + best * dir;
    return best;
  }

  cv::Mat Render(const Eigen::Isometry3d& world_to_camera, const PinholeCamera& camera) const {
    cv::Mat image(camera.height, camera.width, CV_32FC1);
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        Eigen::Vector3d X;
        const double z = DepthAt(world_to_camera, camera, x, y, &X);
        image.at<float>(y, x) = std::isfinite(z) ? static_cast<float>(Texture(X)) : 128.0f;
      }
    }
    return image;
  }
};

// Camera-to-world trajectory moving forward and sideways with a slight yaw.
inline Eigen::Isometry3d TruePose(int i) {
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();
  T_wc.translation() = Eigen::Vector3d(0.15 * i, -0.03 * i, 0.35 * i);
  T_wc.linear() = ExpSO3(Eigen::Vector3d(0.004 * i, -0.012 * i, 0.003 * i));
  return T_wc.inverse();  // world-to-camera
}

}  // namespace dvso::vo::testing
