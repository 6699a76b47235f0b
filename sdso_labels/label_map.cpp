#include "sdso_labels/label_map.h"

#include <cmath>

#include "core/error.h"

namespace dvso::labels {

void LabelProjectionOptions::Check() const {
  Require(occlusion_radius >= 0 && occlusion_radius <= 10, "labels: occlusion_radius must be in [0, 10]");
  Require(occlusion_margin >= 0, "labels: occlusion_margin must be >= 0");
  Require(min_depth > 0, "labels: min_depth must be > 0");
  Require(max_disparity > 0 && max_disparity < 256, "labels: max_disparity must be in (0, 256)");
  Require(edge_radius >= 0 && edge_radius <= 10, "labels: edge_radius must be in [0, 10]");
  Require(edge_margin >= 0, "labels: edge_margin must be >= 0");
}

int RenderLabelMap(const std::vector<LabelPoint>& points, const Eigen::Isometry3d& T_world_camera,
                   const StereoCamera& camera, const LabelProjectionOptions& options, cv::Mat* label_map) {
  const PinholeCamera& cam = camera.left;
  const Eigen::Isometry3d T_camera_world = T_world_camera.inverse();
  struct Projected {
    int x, y;
    float disparity;
  };
  std::vector<Projected> projected;
  projected.reserve(points.size());
  for (const auto& p : points) {
    const Eigen::Vector3d pc = T_camera_world * p.position_world;
    if (pc.z() < options.min_depth) continue;
    const Eigen::Vector2d uv = cam.Project(pc);
    const int x = static_cast<int>(std::lround(uv.x()));
    const int y = static_cast<int>(std::lround(uv.y()));
    if (x < 0 || y < 0 || x >= cam.width || y >= cam.height) continue;
    const double disparity = camera.FxB() / pc.z();
    if (disparity > options.max_disparity) continue;
    projected.push_back({x, y, static_cast<float>(disparity)});
  }
  // Z-buffer with splats: the largest disparity (nearest point) within the
  // occlusion radius of each pixel, and the smallest (farthest point) within
  // the edge radius.
  cv::Mat nearest(cam.height, cam.width, CV_32F, cv::Scalar(0));
  cv::Mat farthest;
  if (options.edge_radius > 0) farthest = cv::Mat(cam.height, cam.width, CV_32F, cv::Scalar(1e9));
  const int r = options.occlusion_radius, e = options.edge_radius;
  for (const auto& p : projected) {
    for (int y = std::max(0, p.y - r); y <= std::min(cam.height - 1, p.y + r); ++y) {
      float* row = nearest.ptr<float>(y);
      for (int x = std::max(0, p.x - r); x <= std::min(cam.width - 1, p.x + r); ++x) {
        row[x] = std::max(row[x], p.disparity);
      }
    }
    for (int y = std::max(0, p.y - e); e > 0 && y <= std::min(cam.height - 1, p.y + e); ++y) {
      float* row = farthest.ptr<float>(y);
      for (int x = std::max(0, p.x - e); x <= std::min(cam.width - 1, p.x + e); ++x) {
        row[x] = std::min(row[x], p.disparity);
      }
    }
  }
  *label_map = cv::Mat(cam.height, cam.width, CV_32F, cv::Scalar(0));
  int count = 0;
  for (const auto& p : projected) {
    const float front = nearest.at<float>(p.y, p.x);
    if (p.disparity * (1.0 + options.occlusion_margin) < front) continue;  // hidden behind a nearer point
    if (e > 0 && farthest.at<float>(p.y, p.x) * (1.0 + options.edge_margin) < p.disparity) continue;  // depth edge
    float& label = label_map->at<float>(p.y, p.x);
    if (label == 0.f) ++count;
    label = std::max(label, p.disparity);
  }
  return count;
}

}  // namespace dvso::labels
