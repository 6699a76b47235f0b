// Least-squares alignment of two corresponding point sets (Umeyama, "Least-
// squares estimation of transformation parameters between two point patterns",
// PAMI 1991). Used by the evaluation to remove the gauge freedom of odometry:
// SE(3) for stereo (metric scale observable), Sim(3) for monocular estimates.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace dvso {

enum class AlignmentMode { kNone, kSE3, kSim3 };

// "none" | "se3" | "sim3" (case-insensitive); throws dvso::Error otherwise.
AlignmentMode ParseAlignmentMode(const std::string& name);
std::string AlignmentModeName(AlignmentMode mode);

// A similarity transform x -> scale * rotation * x + translation.
struct Similarity3 {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return scale * rotation * x + translation; }
  // Applies the transform to a camera-to-world pose: the camera centre moves as
  // a point, the orientation is rotated; the result is again a rigid pose.
  Eigen::Isometry3d Apply(const Eigen::Isometry3d& T_world_camera) const;
};

// Finds the transform minimising sum_i || target_i - (s R source_i + t) ||^2.
// kNone returns the identity, kSE3 fixes s = 1, kSim3 estimates s as well.
// Needs >= 3 pairs (kNone: any); throws dvso::Error when the sizes differ, the
// source points all coincide, or (Sim3) the source has zero spread. Collinear
// points are accepted: the rotation about the line is then arbitrary, which
// does not change any aligned position.
Similarity3 UmeyamaAlignment(const std::vector<Eigen::Vector3d>& source,
                             const std::vector<Eigen::Vector3d>& target, AlignmentMode mode);

}  // namespace dvso
