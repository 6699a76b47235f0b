// LabelWriter: the observer that turns Stereo DSO's optimised sparse points
// into per-frame disparity labels (paper section 3.2, Omega_DSO; section 5.1
// dataset K_o). A frame's labels are written once every keyframe whose points
// label it has been marginalised, so both the points and the poses used are
// final. The keyframes that label a frame ("hosts") are
//   - the keyframes in the window when the frame was tracked,
//   - the `past_keyframes` most recently marginalised ones before that, and
//   - the next `future_keyframes` keyframes created after it
// (in forward motion, far points stay in view over many keyframes). Their
// points are projected with the frame's final pose
// T_world_frame = T_world_ref(final) * T_ref_frame(tracked); keyframes get
// their own points at their exact pixels. Only well-constrained points are
// used (enough good residuals, positive, in range), occluded ones and those
// on depth edges are dropped (label_map.h) and each label is verified on the
// frame's own stereo pair (stereo_check.h). This class does the keyframe
// bookkeeping (which points and poses are final, held with per-keyframe
// reference counts); LabelProducer renders, verifies and writes the maps.
#pragma once

#include <deque>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/camera.h"
#include "sdso_labels/label_map.h"
#include "sdso_labels/label_producer.h"
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
  // The same relative to the image: a point whose static stereo energy exceeds this multiple of
  // the median over its keyframe's labelled points is not labelled. A pattern straddling a
  // silhouette (the main wrong label, docs/labels.md) matches the pair worse than the points
  // inside surfaces; relative to the median, the test follows the sensor noise of the images.
  double max_stereo_energy_ratio = 1.5;
  // ... but never below this energy: 8 pattern pixels x (2 grey levels)^2, a match as good as a
  // clean camera gives (on noise-free images the median is near 0 and the ratio alone would drop
  // points for interpolation errors).
  double stereo_energy_ratio_floor = 32;
  // Keyframes created after a frame whose points also label it (forward motion keeps
  // them in view); 0 = only the window the frame was tracked against. More hosts mean
  // more labels; wrong projections are caught by the stereo check on the frame's own pair.
  // 40 / 20 (session 37, docs/labels.md): +7-22 % labels and -0.01 to +0.74 points within 1 px on 13
  // unseen worlds against 18 / 9 (session 20), where several candidates meet on a pixel the
  // occlusion test keeps the nearest.
  int future_keyframes = 40;
  // Keyframes marginalised before a frame was tracked whose points also label it.
  int past_keyframes = 20;
  // Also label each keyframe with its own candidates whose static stereo match converged
  // (vo::OdometryObserver::OnKeyframeCandidates): the points DSO never activates because
  // they leave the view before the next keyframe, i.e. near objects at the side. They
  // label only their keyframe (at their own pixels, so the pose does not matter) and go
  // through the same occlusion, edge and stereo tests as every label.
  bool keyframe_candidates = false;
  bool overwrite = false;            // rewrite label files that already exist (else resume: keep them)
  // Also write right-image labels (out_dir/right/; paper eq. of L_s uses both images).
  bool right_labels = false;
  LabelProjectionOptions projection = DefaultProjection();  // occlusion/edge handling, ranges
  StereoCheckOptions stereo_check = DefaultStereoCheck();   // test on the labelled frame's own pair

  void Check() const;
  // Label-mode defaults of the generic options (measurements: configs/labels_default.yaml).
  static LabelProjectionOptions DefaultProjection();
  static StereoCheckOptions DefaultStereoCheck();
};

using LabelWriterCounters = LabelCounters;

class LabelWriter : public vo::OdometryObserver {
 public:
  // Writes `out_dir/%06d.png` for every tracked frame (KITTI uint16, *256,
  // 0 = no label), atomically. `sink` (optional) also gets every map, e.g.
  // for statistics against ground truth. Without `loader` the stereo check is
  // skipped. With `worker_thread` the maps are produced on a worker thread
  // (sink and loader are then called from it); all are written when
  // OnFinished() returns. `right_sink` gets the right-image maps (options.right_labels).
  LabelWriter(const StereoCamera& camera, const LabelOptions& options, std::string out_dir, LabelSink sink = {},
              StereoPairLoader loader = {}, bool worker_thread = false, LabelSink right_sink = {});

  void OnFrameTracked(const vo::FrameEvent& event) override;
  void OnWindowOptimized(const vo::WindowEvent& event) override;
  void OnPointsMarginalized(const std::vector<vo::PointInfo>& points) override;
  void OnKeyframeMarginalized(const vo::KeyframeInfo& keyframe) override;
  void OnKeyframeCandidates(int keyframe_frame_index, const std::vector<vo::PointInfo>& candidates) override;
  void OnReset(int frame_index) override;
  void OnFinished() override;

  int frames_written() const { return producer_.frames_written(); }
  int frames_pending() const { return static_cast<int>(pending_.size()); }
  // Keyframes whose points or poses are still held (memory stays bounded).
  int hosts_held() const { return static_cast<int>(hosts_.size()); }
  // Complete once OnFinished() returned.
  const LabelCounters& counters() const { return producer_.counters(); }

 private:
  struct PendingFrame {
    int frame_index;
    int reference;                  // keyframe frame index, -1 = none (lost / initialising)
    Eigen::Isometry3d T_ref_frame;  // or T_world_frame when reference == -1
    std::vector<int> hosts;         // keyframes whose points label this frame (includes reference)
    int future_hosts_wanted = 0;    // later keyframes still to be added to hosts
  };
  // A keyframe some pending frame needs: its final points and pose once marginalised.
  struct Host {
    std::vector<vo::PointInfo> points;  // final values of well-constrained points
    std::vector<LabelPoint> world;      // the same in the world frame (once final)
    Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // final pose
    bool final = false;                 // marginalised: points and pose are final
    int users = 0;                      // pending frames (+1 while among the recent past keyframes)
  };

  bool InDepthRange(const vo::PointInfo& point) const;  // positive inverse depth, not beyond max_depth
  void ForgetActivatedCandidates(const std::vector<vo::PointInfo>& active_points);
  bool Usable(const vo::PointInfo& point) const;
  void AddUser(int host);
  void RemoveUser(int host);
  void ReleaseRecentPast();  // drops the hold of every recent past keyframe
  bool Ready(const PendingFrame& frame) const;
  void FlushReady();
  void Write(const PendingFrame& frame);

  StereoCamera camera_;
  LabelOptions options_;
  std::vector<int> window_;             // keyframes in the window after the last optimisation
  std::deque<int> recent_past_;         // last past_keyframes marginalised keyframes (same map)
  std::deque<PendingFrame> pending_;    // in input order
  std::map<int, Host> hosts_;           // by keyframe frame index; erased when users drop to 0
  // With options.keyframe_candidates: stereo-matched candidates of keyframes whose own
  // frame is not written yet (host pixel and inverse depth), by keyframe frame index.
  std::map<int, std::vector<vo::PointInfo>> keyframe_candidates_;
  LabelProducer producer_;               // renders, verifies and writes the maps
};

}  // namespace dvso::labels
