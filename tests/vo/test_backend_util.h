// Synthetic data for the backend tests: images from closed-form functions and
// a small ray-cast scene of textured planes seen from known poses.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "core/camera.h"
#include "core/lie.h"
#include "vo/frame/image_pyramid.h"
#include "vo/optimization/window.h"

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
  const Eigen::Vector3d Y = 2.0 * X;  // image periods of ~20-60 px at the scene depths
  return 128.0 + 38.0 * std::sin(3.1 * Y.x() + 1.3 * Y.y()) + 28.0 * std::sin(2.3 * Y.y() - 1.7 * Y.z() + 0.5) +
         24.0 * std::sin(4.1 * Y.z() + 2.9 * Y.x()) + 18.0 * std::sin(5.3 * Y.x() - 4.7 * Y.y() + 1.1) +
         12.0 * std::sin(7.9 * Y.y() + 6.1 * Y.x() + 0.3 * Y.z());
}

// A "room" of planes n . X = d (world frame): back wall, floor, side walls.
struct PlaneScene {
  std::vector<Eigen::Vector4d> planes = {
      {0, 0, 1, 7.0},    // back wall z = 7
      {0, 1, 0, 1.5},    // floor y = 1.5 (y points down)
      {1, 0, 0, -3.0},   // left wall x = -3
      {1, 0, 0, 3.5},    // right wall x = 3.5
  };

  // Depth (camera z) of the first surface hit by the ray through (u, v); +inf if none.
  double DepthAt(const Eigen::Isometry3d& world_to_camera, const PinholeCamera& camera, double u, double v,
                 Eigen::Vector3d* world_point = nullptr, int* plane_index = nullptr) const {
    const Eigen::Isometry3d camera_to_world = world_to_camera.inverse();
    const Eigen::Vector3d origin = camera_to_world.translation();
    const Eigen::Vector3d ray_cam = camera.Unproject(u, v);  // z = 1
    const Eigen::Vector3d dir = camera_to_world.linear() * ray_cam;
    double best = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < planes.size(); ++i) {
      const Eigen::Vector4d& p = planes[i];
      const double denom = p.head<3>().dot(dir);
      if (std::abs(denom) < 1e-12) continue;
      const double s = (p(3) - p.head<3>().dot(origin)) / denom;  // s = camera z since ray z = 1
      if (s > 0.1 && s < best) {
        best = s;
        if (plane_index != nullptr) *plane_index = static_cast<int>(i);
      }
    }
    if (world_point != nullptr && std::isfinite(best)) *world_point = origin + best * dir;
    return best;
  }

  // 3x3 supersampled (box filter over the pixel) to limit aliasing.
  cv::Mat Render(const Eigen::Isometry3d& world_to_camera, const PinholeCamera& camera) const {
    cv::Mat image(camera.height, camera.width, CV_32FC1);
    for (int y = 0; y < camera.height; ++y) {
      for (int x = 0; x < camera.width; ++x) {
        double sum = 0.0;
        for (int sy = -1; sy <= 1; ++sy) {
          for (int sx = -1; sx <= 1; ++sx) {
            Eigen::Vector3d X;
            const double z = DepthAt(world_to_camera, camera, x + sx / 3.0, y + sy / 3.0, &X);
            sum += std::isfinite(z) ? Texture(X) : 128.0;
          }
        }
        image.at<float>(y, x) = static_cast<float>(sum / 9.0);
      }
    }
    return image;
  }

  // True when the whole neighbourhood of radius r around (u, v) lies on one plane.
  bool OnSinglePlane(const Eigen::Isometry3d& world_to_camera, const PinholeCamera& camera, double u, double v,
                     double r) const {
    int first = -1;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        int index = -1;
        DepthAt(world_to_camera, camera, u + dx * r, v + dy * r, nullptr, &index);
        if (first < 0) first = index;
        if (index != first || index < 0) return false;
      }
    }
    return true;
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

namespace dvso::vo::testing {

// A window over the plane scene: keyframes at TruePose(0..n-1) (optionally
// perturbed), points on a grid of well-textured pixels hosted in the first
// `num_hosts` keyframes with their true inverse depths (optionally perturbed).
struct SceneWindow {
  StereoCamera camera;
  std::unique_ptr<Window> window;
  std::vector<Eigen::Isometry3d> true_world_to_camera;
  std::map<int, double> true_idepth;  // point id -> inverse depth
};

struct SceneWindowSpec {
  int num_keyframes = 4;
  int num_hosts = 2;
  int grid_step = 12;                 // pixel spacing of candidate points
  bool stereo = false;                // right images (static stereo)
  bool virtual_stereo = false;        // D^R from the true right depth
  double pose_noise_t = 0.0;          // metres, per component (keyframes > 0)
  double pose_noise_r = 0.0;          // radians, per component (keyframes > 0)
  double idepth_noise = 0.0;          // relative
  double scale = 1.0;                 // initial translations and depths scaled by this (mono gauge)
  unsigned seed = 1;
  int width = 320, height = 240;
};

inline SceneWindow BuildSceneWindow(const WindowOptions& options, const SceneWindowSpec& spec) {
  SceneWindow sw;
  sw.camera.left = SmallCamera(spec.width, spec.height);
  sw.camera.baseline = 0.5;
  sw.window = std::make_unique<Window>(options, sw.camera);
  const PlaneScene scene;
  std::mt19937 rng(spec.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < spec.num_keyframes; ++i) {
    const Eigen::Isometry3d T = TruePose(i);
    sw.true_world_to_camera.push_back(T);
    KeyframeInput in;
    in.id = 10 * i;
    const cv::Mat image = scene.Render(T, sw.camera.left);
    in.left = MakePyramid(image, sw.camera.left);
    Eigen::Isometry3d right_T = T;
    right_T.translation().x() -= sw.camera.baseline;  // right camera at +B along x
    if (spec.stereo) in.right = MakePyramid(scene.Render(right_T, sw.camera.left), sw.camera.left);
    if (spec.virtual_stereo) {
      in.right_disparity = cv::Mat(spec.height, spec.width, CV_32FC1);
      for (int y = 0; y < spec.height; ++y)
        for (int x = 0; x < spec.width; ++x)
          in.right_disparity.at<float>(y, x) =
              static_cast<float>(sw.camera.FxB() / scene.DepthAt(right_T, sw.camera.left, x, y));
    }
    Eigen::Isometry3d T0 = T;
    T0.translation() *= spec.scale;
    if (i > 0) {
      Vector6d xi;
      for (int k = 0; k < 3; ++k) xi(k) = spec.pose_noise_t * normal(rng);
      for (int k = 3; k < 6; ++k) xi(k) = spec.pose_noise_r * normal(rng);
      T0 = ExpSE3(xi) * T0;
    }
    in.world_to_camera = T0;
    sw.window->AddKeyframe(in);
  }
  for (int h = 0; h < spec.num_hosts; ++h) {
    const Keyframe& host = sw.window->keyframe(h);
    const PyramidLevel& level = host.left->level(0);
    for (int y = 16; y < spec.height - 16; y += spec.grid_step) {
      for (int x = 16; x < spec.width - 16; x += spec.grid_step) {
        if (level.GradSq(x, y) < 25.0f) continue;
        if (!scene.OnSinglePlane(sw.true_world_to_camera[h], sw.camera.left, x, y, 4.0)) continue;
        const double z = scene.DepthAt(sw.true_world_to_camera[h], sw.camera.left, x, y);
        const double d = 1.0 / z;
        const double d0 = d * std::max(0.3, 1.0 + spec.idepth_noise * normal(rng)) / spec.scale;
        const int id = sw.window->AddPoint(host.id, static_cast<float>(x), static_cast<float>(y), d0);
        if (id >= 0) sw.true_idepth[id] = d;
      }
    }
  }
  return sw;
}

}  // namespace dvso::vo::testing
