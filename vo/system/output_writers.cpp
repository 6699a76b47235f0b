#include "vo/system/output_writers.h"

#include <cstdio>
#include <iomanip>
#include <unistd.h>

#include "core/error.h"
#include "core/fs_util.h"

namespace dvso::vo {

namespace {
// Resident set size of this process (Linux /proc/self/statm; 0 elsewhere), so
// that a run log shows whether memory stays flat over a long sequence.
double ResidentSetMegabytes() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return 0.0;
  return static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}
}  // namespace

void TrajectoryRecorder::OnFrameTracked(const FrameEvent& e) {
  Record r;
  r.timestamp = e.timestamp;
  r.reference = e.reference_frame_index;
  r.pose = e.reference_frame_index >= 0 ? e.T_ref_frame : e.T_world_camera;
  if (e.reference_frame_index >= 0 && keyframe_poses_.count(e.reference_frame_index) == 0) {
    // Reference not reported yet (e.g. mono initialisation): remember its current estimate.
    keyframe_poses_[e.reference_frame_index] = e.T_world_camera * e.T_ref_frame.inverse();
  }
  if (e.status == FrameStatus::kKeyframe) keyframe_poses_[e.frame_index] = e.T_world_camera;
  records_.push_back(r);
  statuses_.push_back(e.status);
  indices_.push_back(e.frame_index);
}

void TrajectoryRecorder::OnWindowOptimized(const WindowEvent& e) {
  for (const KeyframeInfo& k : e.keyframes) keyframe_poses_[k.frame_index] = k.T_world_camera;
}

void TrajectoryRecorder::OnKeyframeMarginalized(const KeyframeInfo& k) {
  keyframe_poses_[k.frame_index] = k.T_world_camera;
}

Trajectory TrajectoryRecorder::Resolve() const {
  Trajectory t;
  t.poses.reserve(records_.size());
  for (const Record& r : records_) {
    StampedPose p;
    p.timestamp = r.timestamp;
    if (r.reference >= 0) {
      const auto it = keyframe_poses_.find(r.reference);
      Require(it != keyframe_poses_.end(), "trajectory: unknown reference keyframe " + std::to_string(r.reference));
      p.T_world_camera = it->second * r.pose;
    } else {
      p.T_world_camera = r.pose;
    }
    t.poses.push_back(p);
  }
  return t;
}

int TrajectoryRecorder::CountStatus(FrameStatus status) const {
  int n = 0;
  for (FrameStatus s : statuses_) n += s == status;
  return n;
}

RunLogWriter::RunLogWriter(const std::string& csv_path)
    : path_(csv_path), partial_path_(csv_path + ".partial"), out_(partial_path_) {
  RequireFile(out_.good(), partial_path_, "cannot write run log");
  out_ << "frame,timestamp,status,segment,reference,track_ms,optimize_ms,total_ms,rmse,hypotheses,"
          "window_keyframes,active_points,immature_points,keyframe_score,rmse_ratio,"
          "virtual_stereo_residuals,virtual_stereo_energy,stereo_gain,stereo_bias,stereo_radial,stereo_radial_keyframe,rss_mb\n";
}

RunLogWriter::~RunLogWriter() {
  // A run that failed leaves no half-written log behind.
  if (!finished_) {
    out_.close();
    std::remove(partial_path_.c_str());
  }
}

void RunLogWriter::OnFrameTracked(const FrameEvent& e) {
  out_ << e.frame_index << ',' << std::setprecision(15) << e.timestamp << ',' << ToString(e.status) << ','
       << e.segment << ',' << e.reference_frame_index << ',' << std::setprecision(6) << e.track_ms << ','
       << e.optimize_ms << ',' << e.total_ms << ',' << e.tracking_rmse << ',' << e.hypotheses_tried << ','
       << e.window_keyframes << ',' << e.active_points << ',' << e.immature_points << ',' << e.keyframe_score << ','
       << e.rmse_ratio << ',' << e.virtual_stereo_residuals << ',' << e.virtual_stereo_energy << ','
       << e.stereo_gain << ',' << e.stereo_bias << ',' << e.stereo_radial << ',' << e.stereo_radial_keyframe << ','
       << std::setprecision(4) << ResidentSetMegabytes() << '\n';
}

void RunLogWriter::OnFinished() {
  out_.flush();
  RequireFile(out_.good(), path_, "write failed (disk full?)");
  out_.close();
  RequireFile(std::rename(partial_path_.c_str(), path_.c_str()) == 0, path_, "cannot rename the finished run log");
  finished_ = true;
}

PlyPointWriter::PlyPointWriter(const std::string& ply_path, int min_good_residuals)
    : path_(ply_path), body_path_(ply_path + ".body.tmp"), body_(body_path_), min_good_residuals_(min_good_residuals) {
  RequireFile(body_.good(), body_path_, "cannot write point cloud");
}

PlyPointWriter::~PlyPointWriter() {
  body_.close();
  std::remove(body_path_.c_str());  // gone already after OnFinished
}

void PlyPointWriter::OnPointsMarginalized(const std::vector<PointInfo>& points) {
  for (const PointInfo& p : points) {
    if (p.num_good_residuals < min_good_residuals_ || !p.world.allFinite()) continue;
    body_ << static_cast<float>(p.world.x()) << ' ' << static_cast<float>(p.world.y()) << ' '
          << static_cast<float>(p.world.z()) << '\n';
    ++count_;
  }
}

void PlyPointWriter::OnFinished() {
  body_.close();  // flushes the last points: a failure here would leave the header's count above the body's
  RequireFile(!body_.fail(), path_, "write failed (disk full?)");
  WriteStreamAtomically(path_, [this](std::ostream& out) {
    out << "ply\nformat ascii 1.0\nelement vertex " << count_
        << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    if (count_ > 0) {
      std::ifstream body(body_path_);
      out << body.rdbuf();
    }
  });
  std::remove(body_path_.c_str());
}

}  // namespace dvso::vo
