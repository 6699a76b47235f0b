// Observers that write the odometry's results:
//  - TrajectoryRecorder: every frame's pose, resolved at the end against the
//    final (marginalised) keyframe poses: T_world_frame = T_world_ref * T_ref_frame,
//    so refinements of keyframes by the window reach the non-keyframes too.
//    Keeps one small record per frame (memory O(frames) * ~150 bytes).
//  - RunLogWriter: one CSV line per frame (status, timings, window sizes, RSS),
//    streamed to disk.
//  - PlyPointWriter: marginalised points streamed to a temporary file,
//    assembled into a binary-free ASCII PLY at the end.
#pragma once

#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "core/trajectory.h"
#include "vo/system/observer.h"

namespace dvso::vo {

class TrajectoryRecorder : public OdometryObserver {
 public:
  void OnFrameTracked(const FrameEvent& event) override;
  void OnWindowOptimized(const WindowEvent& event) override;
  void OnKeyframeMarginalized(const KeyframeInfo& keyframe) override;

  // Camera-to-world poses of all frames seen so far, in input order.
  Trajectory Resolve() const;
  const std::vector<FrameStatus>& statuses() const { return statuses_; }
  const std::vector<int>& frame_indices() const { return indices_; }
  int CountStatus(FrameStatus status) const;

 private:
  struct Record {
    double timestamp;
    int reference;                // keyframe frame index or -1
    Eigen::Isometry3d pose;       // T_ref_frame (reference >= 0) or T_world_frame
  };
  std::vector<Record> records_;
  std::vector<FrameStatus> statuses_;
  std::vector<int> indices_;
  std::map<int, Eigen::Isometry3d> keyframe_poses_;  // latest T_world_camera per keyframe frame index
};

class RunLogWriter : public OdometryObserver {
 public:
  // Streams into csv_path + ".partial", renamed to csv_path by OnFinished;
  // a run that never finishes leaves no log (the partial file is removed).
  explicit RunLogWriter(const std::string& csv_path);
  ~RunLogWriter() override;
  void OnFrameTracked(const FrameEvent& event) override;
  void OnFinished() override;

 private:
  std::string path_, partial_path_;
  std::ofstream out_;
  bool finished_ = false;
};

class PlyPointWriter : public OdometryObserver {
 public:
  // Keeps points with at least `min_good_residuals` good temporal residuals.
  PlyPointWriter(const std::string& ply_path, int min_good_residuals = 1);
  // A run that failed leaves neither the PLY nor its temporary body behind.
  ~PlyPointWriter() override;
  void OnPointsMarginalized(const std::vector<PointInfo>& points) override;
  void OnFinished() override;
  long num_points() const { return count_; }

 private:
  std::string path_, body_path_;
  std::ofstream body_;
  int min_good_residuals_;
  long count_ = 0;
};

}  // namespace dvso::vo
