// Sparse disparity label maps (paper section 3.2 "Supervised loss": the
// supervision Omega_DSO comes from Stereo DSO's optimised sparse points).
// Projects optimised 3D points into a frame and keeps only visible ones.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.h"

namespace dvso::labels {

struct LabelPoint {
  Eigen::Vector3d position_world;  // optimised 3D point (world frame)
};

struct LabelProjectionOptions {
  int occlusion_radius = 2;             // px: a nearer point within this radius hides a farther one
  double occlusion_margin = 0.05;       // relative disparity margin before a point counts as hidden
  double min_depth = 0.5;               // m: points closer than this are not labelled
  double max_disparity = 255.0;         // px: larger disparities are dropped (uint16 /256 range)
  // Depth edges: a point with a markedly farther point within this radius lies on an
  // occlusion boundary (silhouette), where a one-pixel position error swaps foreground
  // and background; it is not labelled. 0 = off.
  int edge_radius = 0;
  double edge_margin = 0.1;             // relative disparity difference that counts as an edge

  void Check() const;
};

// Renders the points into a CV_32F disparity map (fx * baseline / z) of the
// camera's size for a frame with pose T_world_camera; 0 = no label. A point
// is dropped when out of bounds, behind/too close to the camera, or occluded
// by a nearer point inside occlusion_radius, or on a depth edge (a farther
// point inside edge_radius). Returns the number of labels.
int RenderLabelMap(const std::vector<LabelPoint>& points, const Eigen::Isometry3d& T_world_camera,
                   const StereoCamera& camera, const LabelProjectionOptions& options, cv::Mat* label_map);

}  // namespace dvso::labels
