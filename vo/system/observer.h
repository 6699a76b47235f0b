// Events the odometry System emits. Observers (trajectory writer, run log,
// point cloud, label writer of sdso_labels/) receive data; nothing reaches
// into the optimiser to pull it out. All methods default to no-ops.
// Frame indices are the input frame indices given to System::ProcessFrame;
// keyframes are identified by the frame index they were created from.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace dvso::vo {

enum class FrameStatus {
  kTracked,       // tracked against the reference keyframe
  kKeyframe,      // tracked (or initialised) and made a keyframe
  kInitializing,  // waiting for (mono) initialisation: pose is a placeholder
  kLost,          // tracking failed: pose is the best available prediction
  kUnreadable,    // the image could not be read: not processed, pose is the last one (a lost frame)
};
std::string ToString(FrameStatus status);

struct FrameEvent {
  int frame_index = 0;
  double timestamp = 0;
  FrameStatus status = FrameStatus::kTracked;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // current estimate
  // Pose relative to the reference keyframe (refined later by the window):
  // T_world_camera = T_world_ref * T_ref_frame. reference_frame_index = -1 when
  // the pose is not attached to a keyframe (lost / initialising frames).
  int reference_frame_index = -1;
  Eigen::Isometry3d T_ref_frame = Eigen::Isometry3d::Identity();
  int segment = 0;             // increments at every (re-)initialisation after a loss
  double tracking_rmse = 0;
  int hypotheses_tried = 0;
  double keyframe_score = 0;   // DSO flow/affine score (> 1 = keyframe), 0 when not tracked
  double rmse_ratio = 0;       // tracking rmse / first rmse after the reference (> growth factor = keyframe)
  double track_ms = 0;         // pyramid + tracking
  double total_ms = 0;         // everything for this frame (incl. keyframe work)
  double optimize_ms = 0;      // windowed optimisation (keyframes only)
  int window_keyframes = 0;
  int active_points = 0;
  int immature_points = 0;
  // Virtual stereo term (eq. 5.8) after the last window optimisation: active
  // residuals and their total weighted energy (0 outside DVSO mode).
  int virtual_stereo_residuals = 0;
  double virtual_stereo_energy = 0;
  // Stereo mode: the newest stereo keyframe's brightness transfer I_right ~ gain * (1 + radial rho^2) *
  // I_left + bias (vo/frame/stereo_brightness.h); 1, 0, 0 until the first one and in the other modes.
  // stereo_radial is the radial term used (pooled over keyframes, RadialTermPool), and
  // stereo_radial_keyframe that keyframe's own fit of it (NaN where it had none, 0 with the term off).
  double stereo_gain = 1.0;
  double stereo_bias = 0.0;
  double stereo_radial = 0.0;
  double stereo_radial_keyframe = 0.0;
};

struct PointInfo {
  int host_frame_index = -1;
  float u = 0, v = 0;          // host pixel, level 0
  double idepth = 0;           // inverse depth in the host camera
  Eigen::Vector3d world = Eigen::Vector3d::Zero();
  int num_good_residuals = 0;  // temporal residuals in the active state at the last evaluation
  int num_residuals = 0;       // all residuals (incl. stereo kinds)
  float idepth_hessian = 0;    // information on the inverse depth (H_dd over active residuals)
  float mean_energy = 0;       // mean energy over its active residuals at the last evaluation
  float stereo_energy = -1;    // energy of its static stereo residual (also when rejected as an outlier), -1 if none
};

struct KeyframeInfo {
  int frame_index = -1;
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  double affine_a = 0, affine_b = 0;
};

struct WindowEvent {
  int frame_index = -1;                 // the keyframe that triggered the optimisation
  std::vector<KeyframeInfo> keyframes;  // oldest first
  std::vector<PointInfo> points;        // all active points
};

class OdometryObserver {
 public:
  virtual ~OdometryObserver() = default;
  virtual void OnFrameTracked(const FrameEvent& /*event*/) {}
  virtual void OnWindowOptimized(const WindowEvent& /*event*/) {}
  virtual void OnPointsMarginalized(const std::vector<PointInfo>& /*points*/) {}
  virtual void OnKeyframeMarginalized(const KeyframeInfo& /*keyframe*/) {}
  // Stereo mode: the candidates of a new keyframe whose static stereo match is
  // good enough for activation (ImmaturePoint::ReadyForActivation), with host
  // pixel and inverse depth from that match. DSO activates a candidate only at
  // the next keyframe and only if it projects into it, so points that leave
  // the view before (near objects at the side) never become active points.
  virtual void OnKeyframeCandidates(int /*keyframe_frame_index*/, const std::vector<PointInfo>& /*candidates*/) {}
  // Tracking was lost at frame_index; the window is discarded (its keyframes
  // were reported through OnKeyframeMarginalized before).
  virtual void OnReset(int /*frame_index*/) {}
  virtual void OnFinished() {}
};

}  // namespace dvso::vo
