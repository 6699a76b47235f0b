#include "sdso_labels/label_writer.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"

namespace dvso::labels {

void LabelOptions::Check() const {
  Require(min_good_residuals >= 0, "labels: min_good_residuals must be >= 0");
  Require(max_depth > projection.min_depth, "labels: max_depth must exceed projection.min_depth");
  Require(max_disparity_stddev > 0, "labels: max_disparity_stddev must be > 0");
  Require(max_mean_energy > 0 && max_stereo_energy > 0, "labels: energy thresholds must be > 0");
  Require(future_keyframes >= 0 && future_keyframes <= 20, "labels: future_keyframes must be in [0, 20]");
  stereo_check.Check();
  projection.Check();
}

LabelWriter::LabelWriter(const StereoCamera& camera, const LabelOptions& options, std::string out_dir,
                         LabelSink sink, StereoPairLoader loader)
    : camera_(camera),
      options_(options),
      out_dir_(std::move(out_dir)),
      sink_(std::move(sink)),
      loader_(std::move(loader)) {
  options_.Check();
  camera_.Check();
  EnsureDirectory(out_dir_);
}

void LabelWriter::OnWindowOptimized(const vo::WindowEvent& event) {
  window_.clear();
  for (const auto& kf : event.keyframes) window_.push_back(kf.frame_index);
  // A new keyframe also labels the earlier frames still waiting for later keyframes.
  const int newest = event.frame_index;
  for (PendingFrame& frame : pending_) {
    if (frame.future_hosts_wanted <= 0 || newest <= frame.frame_index) continue;
    if (std::find(frame.hosts.begin(), frame.hosts.end(), newest) != frame.hosts.end()) continue;
    frame.hosts.push_back(newest);
    ++host_points_[newest].users;
    --frame.future_hosts_wanted;
  }
}

void LabelWriter::OnReset(int /*frame_index*/) {
  // Keyframes of the next map live in another world frame: never mix them in.
  for (PendingFrame& frame : pending_) frame.future_hosts_wanted = 0;
  FlushReady();
}

void LabelWriter::OnFrameTracked(const vo::FrameEvent& event) {
  PendingFrame frame{event.frame_index, event.reference_frame_index,
                     event.reference_frame_index >= 0 ? event.T_ref_frame : event.T_world_camera, {}, 0};
  if (frame.reference >= 0) {
    frame.future_hosts_wanted = options_.future_keyframes;
    frame.hosts = window_;
    if (std::find(frame.hosts.begin(), frame.hosts.end(), frame.reference) == frame.hosts.end()) {
      frame.hosts.push_back(frame.reference);
    }
    for (int host : frame.hosts) ++host_points_[host].users;
  }
  pending_.push_back(std::move(frame));
  FlushReady();
}

void LabelWriter::OnPointsMarginalized(const std::vector<vo::PointInfo>& points) {
  for (const auto& p : points) {
    if (p.num_good_residuals < options_.min_good_residuals || !(p.idepth > 0)) continue;
    if (1.0 / p.idepth > options_.max_depth) continue;
    if (!(p.idepth_hessian > 0) || camera_.FxB() / std::sqrt(p.idepth_hessian) > options_.max_disparity_stddev) continue;
    if (p.mean_energy > options_.max_mean_energy) continue;
    if (p.stereo_energy >= 0 && p.stereo_energy > options_.max_stereo_energy) continue;
    // Points of a host no pending frame needs are of no use any more.
    auto it = host_points_.find(p.host_frame_index);
    if (it == host_points_.end()) continue;
    it->second.points.push_back(p);
  }
}

void LabelWriter::OnKeyframeMarginalized(const vo::KeyframeInfo& keyframe) {
  final_poses_[keyframe.frame_index] = keyframe.T_world_camera;
  FlushReady();
}

void LabelWriter::OnFinished() {
  for (PendingFrame& frame : pending_) frame.future_hosts_wanted = 0;
  FlushReady();
  // Whatever is left could not be finalised (its keyframes never reached the
  // window's end); write it with what is known so every frame has a file.
  while (!pending_.empty()) {
    Write(pending_.front());
    pending_.erase(pending_.begin());
  }
}

bool LabelWriter::Ready(const PendingFrame& frame) const {
  if (frame.future_hosts_wanted > 0) return false;
  for (int host : frame.hosts) {
    if (final_poses_.count(host) == 0) return false;
  }
  return true;
}

void LabelWriter::FlushReady() {
  // Frames are written in input order, so a resumed run never leaves holes.
  while (!pending_.empty() && Ready(pending_.front())) {
    Write(pending_.front());
    pending_.erase(pending_.begin());
  }
}

void LabelWriter::Write(const PendingFrame& frame) {
  cv::Mat labels(camera_.left.height, camera_.left.width, CV_32F, cv::Scalar(0));
  if (frame.reference >= 0 && final_poses_.count(frame.reference) > 0) {
    const Eigen::Isometry3d T_world_frame = final_poses_.at(frame.reference) * frame.T_ref_frame;
    std::vector<LabelPoint> points;
    for (int host : frame.hosts) {
      auto it = host_points_.find(host);
      auto pose = final_poses_.find(host);
      if (it == host_points_.end() || pose == final_poses_.end()) continue;
      for (const auto& p : it->second.points) {
        // Re-derive the world point from the host's final pose.
        const Eigen::Vector3d in_host = camera_.left.Unproject(p.u, p.v) / p.idepth;
        points.push_back({pose->second * in_host});
      }
    }
    RenderLabelMap(points, T_world_frame, camera_, options_.projection, &labels);
    if (loader_ && options_.stereo_check.enabled) {
      cv::Mat left, right;
      loader_(frame.frame_index, &left, &right);
      VerifyLabelsWithStereo(left, right, options_.stereo_check, &labels);
    }
  }
  const std::string path = JoinPath(out_dir_, FrameFileName(frame.frame_index, ".png"));
  if (options_.overwrite || !std::filesystem::exists(path)) WriteKittiMapPng(path, labels);
  if (sink_) sink_(frame.frame_index, labels);
  ++frames_written_;
  for (int host : frame.hosts) {
    auto it = host_points_.find(host);
    if (it != host_points_.end() && --it->second.users <= 0) host_points_.erase(it);
  }
  // Final poses of keyframes no longer referenced can go too (memory stays flat).
  for (auto it = final_poses_.begin(); it != final_poses_.end();) {
    const int id = it->first;
    const bool needed = std::any_of(pending_.begin(), pending_.end(), [id](const PendingFrame& f) {
      return f.reference == id || std::find(f.hosts.begin(), f.hosts.end(), id) != f.hosts.end();
    });
    it = needed || host_points_.count(id) ? std::next(it) : final_poses_.erase(it);
  }
}

}  // namespace dvso::labels
