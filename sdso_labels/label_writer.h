// LabelWriter: the observer that turns Stereo DSO's optimised sparse points
// into per-frame disparity labels (paper section 3.2, Omega_DSO; section 5.1
// dataset K_o). A frame's labels are written once every keyframe that was in
// the window when the frame was tracked has been marginalised, so both the
// points and the poses used are final:
//   - keyframes: their own points (at their exact pixels) plus the other
//     window points projected into them;
//   - other frames: the window's points projected with the final pose
//     T_world_frame = T_world_ref(final) * T_ref_frame(tracked).
// Only well-constrained points are used (enough good residuals, positive,
// in range), and occluded ones are dropped (label_map.h).
#pragma once

#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "core/camera.h"
#include "sdso_labels/label_map.h"
#include "sdso_labels/label_stats.h"
#include "sdso_labels/stereo_check.h"
#include "vo/system/observer.h"

namespace dvso::labels {

struct LabelOptions {
  int min_good_residuals = 2;        // a point needs at least this many good temporal residuals
  double max_depth = 80.0;           // m: farther points are not labelled (KITTI-like depth range)
  // Disparity standard deviation (px) implied by the point's inverse-depth information H_dd,
  // sigma_disp = fx * baseline / sqrt(H_dd), for unit intensity noise; larger = not labelled.
  double max_disparity_stddev = 1e9;
  double max_mean_energy = 1e9;      // mean photometric energy over the point's active residuals
  double max_stereo_energy = 1e9;    // energy of its static stereo residual (ignored when it has none)
  // Keyframes created after a frame whose points also label it (forward motion keeps
  // them in view); 0 = only the window the frame was tracked against.
  int future_keyframes = 5;
  bool overwrite = false;            // rewrite label files that already exist (else resume: keep them)
  LabelProjectionOptions projection; // occlusion handling and ranges of the rendered maps
  StereoCheckOptions stereo_check;   // confidence test on the labelled frame's own stereo pair

  void Check() const;
};

// Receives each finished label map (frame index, CV_32F disparity map).
using LabelSink = std::function<void(int frame_index, const cv::Mat& labels)>;
// Loads the rectified grey pair of a frame (for the stereo check).
using StereoPairLoader = std::function<void(int frame_index, cv::Mat* left, cv::Mat* right)>;

class LabelWriter : public vo::OdometryObserver {
 public:
  // Writes `out_dir/%06d.png` for every tracked frame (KITTI uint16, *256,
  // 0 = no label), atomically. `sink` (optional) also gets every map, e.g.
  // for statistics against ground truth. Without `loader` the stereo check is skipped.
  LabelWriter(const StereoCamera& camera, const LabelOptions& options, std::string out_dir, LabelSink sink = {},
              StereoPairLoader loader = {});

  void OnFrameTracked(const vo::FrameEvent& event) override;
  void OnWindowOptimized(const vo::WindowEvent& event) override;
  void OnPointsMarginalized(const std::vector<vo::PointInfo>& points) override;
  void OnKeyframeMarginalized(const vo::KeyframeInfo& keyframe) override;
  void OnReset(int frame_index) override;
  void OnFinished() override;

  int frames_written() const { return frames_written_; }
  int frames_pending() const { return static_cast<int>(pending_.size()); }

 private:
  struct PendingFrame {
    int frame_index;
    int reference;                  // keyframe frame index, -1 = none (lost / initialising)
    Eigen::Isometry3d T_ref_frame;  // or T_world_frame when reference == -1
    std::vector<int> hosts;         // keyframes whose points label this frame
    int future_hosts_wanted = 0;    // later keyframes still to be added to hosts
  };
  struct HostPoints {
    std::vector<vo::PointInfo> points;  // final values of well-constrained points
    int users = 0;                      // pending frames that need them
  };

  bool Ready(const PendingFrame& frame) const;
  void FlushReady();
  void Write(const PendingFrame& frame);

  StereoCamera camera_;
  LabelOptions options_;
  std::string out_dir_;
  LabelSink sink_;
  StereoPairLoader loader_;
  std::vector<int> window_;                          // keyframes in the window after the last optimisation
  std::vector<PendingFrame> pending_;                // in input order
  std::map<int, HostPoints> host_points_;            // by host keyframe frame index
  std::map<int, Eigen::Isometry3d> final_poses_;     // marginalised keyframes: T_world_camera
  int frames_written_ = 0;
};

}  // namespace dvso::labels
