// Camera trajectories in the two formats people feed to evo and the KITTI
// devkit: KITTI (12 floats per line, row-major 3x4 camera-to-world, one line
// per frame) and TUM ("t tx ty tz qx qy qz qw", camera-to-world).
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace dvso {

enum class TrajectoryFormat { kAuto, kKitti, kTum };

struct StampedPose {
  double timestamp = 0.0;  // seconds; for KITTI files without times, the frame index
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // camera-to-world
};

struct Trajectory {
  std::vector<StampedPose> poses;

  size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
  // Total length of the path (sum of distances between consecutive positions).
  double PathLength() const;
};

// Reads a trajectory; kAuto decides by the number of columns (12 = KITTI,
// 8 = TUM). Lines starting with '#' are comments. KITTI poses get timestamps
// from `times` when given (same length; an error for a TUM file, which has its own), else their line index. Throws
// dvso::Error naming the file and line on any malformed input, including a KITTI 3x3 block that is no
// rotation (|R^T R - I| or |det R - 1| above 1e-3) and a TUM quaternion whose norm is not 1 within 1e-2.
Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format = TrajectoryFormat::kAuto,
                          const std::vector<double>* times = nullptr);

// Writes atomically (temporary file + rename), 12 significant digits (TUM timestamps: 9 decimals).
void WriteKittiTrajectory(const std::string& path, const Trajectory& trajectory);
void WriteTumTrajectory(const std::string& path, const Trajectory& trajectory);

// Reads KITTI's times.txt (one timestamp per line).
std::vector<double> ReadTimes(const std::string& path);

}  // namespace dvso
