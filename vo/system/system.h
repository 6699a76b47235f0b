// The odometry System (DSO's FullSystem): drives, per input frame, the
// pyramid, the coarse tracker against the newest keyframe, the tracing of
// candidate points, the keyframe decision and, for keyframes, the windowed
// bundle adjustment (vo/optimization Window) with marginalisation. Frames are
// streamed: nothing but the window and per-frame bookkeeping is kept, so
// memory stays flat over long sequences. Tracking loss re-initialises and
// continues; every frame is reported to the observers.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "core/camera.h"
#include "core/disparity_source.h"
#include "vo/frame/photometric_calibration.h"
#include "vo/frontend/coarse_tracker.h"
#include "vo/frontend/immature_point.h"
#include "vo/frontend/mono_initializer.h"
#include "vo/system/observer.h"
#include "vo/optimization/window.h"
#include "vo/system/odometry_options.h"

namespace dvso::vo {

class System {
 public:
  // `camera`: rectified intrinsics and baseline (baseline unused in mono).
  // `predictions` (non-owning, must outlive the System) is required when the
  // mode has predictions (DVSO); options.dvso.virtual_baseline must then be
  // resolved (> 0): it converts D^L to inverse depth and is the eq. 5.8 baseline.
  System(const OdometryOptions& options, const StereoCamera& camera, OdometryMode mode,
         DisparitySource* predictions = nullptr);
  ~System();

  void AddObserver(OdometryObserver* observer);  // non-owning; must outlive the System

  // Processes one frame (CV_8UC1 left; right required when the mode has a
  // right image, ignored otherwise). Frames must come in increasing index
  // order. Returns the event sent to observers.
  FrameEvent ProcessFrame(int frame_index, double timestamp, const cv::Mat& left, const cv::Mat& right = cv::Mat());

  // Reports a frame whose image could not be read (a damaged file in a long
  // run): observers get a kUnreadable event with the last pose, so outputs
  // keep one line per input frame; the odometry state is untouched.
  FrameEvent ReportUnreadableFrame(int frame_index, double timestamp);

  // Marginalises what is left (reports final keyframe poses and points) and
  // calls OnFinished. Idempotent.
  void Finish();

  int num_keyframes_total() const { return num_keyframes_total_; }
  int num_resets() const { return segment_; }
  const OdometryOptions& options() const { return options_; }

 private:
  struct KeyframeCandidates {
    int keyframe_id = -1;
    std::vector<ImmaturePoint> points;
  };

  // D^L / D^R of a keyframe-to-be, sanitised, at image resolution.
  struct KeyframePrediction {
    cv::Mat left, right;
  };

  ImagePyramidPtr MakePyramid(const cv::Mat& image) const;
  // The newest stereo keyframe's brightness transfer into a frame's event (every frame reports it).
  void ReportStereoBrightness(FrameEvent* ev) const;
  // The right image's pyramid: its own lens's vignette when right_vignette_file is set.
  ImagePyramidPtr MakeRightPyramid(const cv::Mat& image) const;
  KeyframePrediction FetchPrediction(int frame_index, const cv::Mat& image);
  // A tracked frame that candidates can be traced against.
  struct TraceTarget {
    const ImagePyramid* frame = nullptr;
    Eigen::Isometry3d T_frame_w = Eigen::Isometry3d::Identity();
    double a = 0, b = 0;  // absolute affine brightness parameters of the frame
  };
  // Keyframe-async timing: when the prediction of the pending keyframe has
  // arrived (or `wait`), attaches its D^R and creates its candidates from D^L.
  // With a `late_trace` (a frame already tracked, so its own trace pass has
  // run) the new candidates are traced against it at once: otherwise they
  // miss that frame and reach activation one keyframe later than the
  // blocking schedule's, which on fast motion (nearly every frame a
  // keyframe) leaves the window with a fraction of its points.
  void AttachPendingPrediction(bool wait, const TraceTarget* late_trace = nullptr);
  // Starts a map at this frame with metric depth: static stereo matches of
  // the right image (Stereo DSO) or predicted depths (DVSO).
  void InitializeMetric(int frame_index, const ImagePyramidPtr& left, const cv::Mat& right,
                        const Eigen::Isometry3d& T_world_camera);
  bool StepMonoInitialization(int frame_index, const ImagePyramidPtr& left);
  void MakeKeyframe(int frame_index, const ImagePyramidPtr& left, const cv::Mat& right,
                    const Eigen::Isometry3d& T_cw, double a, double b, FrameEvent* event);
  void TraceCandidates(const TraceTarget& target);
  void TraceCandidateSet(KeyframeCandidates* candidates, const TraceTarget& target);
  void ActivateCandidates(int new_keyframe_id, bool include_new_keyframe);
  // Selects candidate pixels of a new keyframe. With a right pyramid they are
  // stereo matched; with a prediction their search interval comes from D^L
  // (pixels failing the left-right check or without D^L are not selected), and
  // `converged` makes them ready for activation at once (first keyframe).
  // `right_brightness`: the pair's starting transfer, used when `right` is given (MatchStaticStereo).
  void AddCandidates(int keyframe_id, const ImagePyramid& left, const ImagePyramid* right,
                     const StereoBrightness& right_brightness, const KeyframePrediction* prediction, bool converged);
  // Static stereo matching of a keyframe's candidates (Stereo DSO) with the pair's brightness
  // transfer refitted from the matches (vo/frame/stereo_brightness.h); stores the final transfer in the
  // window's keyframe and as the next keyframe's start. Returns the candidates that stay.
  std::vector<ImmaturePoint> MatchStaticStereo(int keyframe_id, std::vector<ImmaturePoint> points,
                                               const ImagePyramid& left, const ImagePyramid& right,
                                               const StereoBrightness& start);
  std::vector<ImmaturePoint> TraceStaticStereo(const std::vector<ImmaturePoint>& points, const ImagePyramid& right,
                                               const StereoBrightness& transfer) const;
  // The transfer refitted from a keyframe's unambiguous static stereo matches, with the intensity range
  // (2nd-98th percentile of the left samples) it was fitted on; none with too few matches. Samples
  // outside either image's unclipped range are left out.
  struct MatchedBrightnessFit {
    StereoBrightness transfer;
    double low = 0, high = 0;
    std::optional<double> keyframe_radial;  // this keyframe's own radial fit, where it has one (transfer.radial
                                            // is the pooled one)
  };
  std::optional<MatchedBrightnessFit> FitStereoBrightnessFromMatches(const std::vector<ImmaturePoint>& traced,
                                                                     const ImagePyramid& left,
                                                                     const ImagePyramid& right,
                                                                     const UnclippedRange& left_unclipped,
                                                                     const UnclippedRange& right_unclipped) const;
  StereoBrightness StartingStereoBrightness(const ImagePyramid& left, const ImagePyramid& right) const;
  void UpdateVirtualStereoStatistics();
  void RunOptimization(FrameEvent* event);
  void MarginalizeKeyframes();
  // Sends points that left the window (marginalised or dropped) to the observers.
  void ReportMarginalizedPoints(const std::vector<MarginalizedPoint>& leaving) const;
  void SetTrackingReference(int keyframe_id);
  void EmitWindowEvent(int frame_index);
  void ResetAfterLoss(int frame_index, const Eigen::Isometry3d& predicted);
  void TrackFrame(int frame_index, const ImagePyramidPtr& pyr, const cv::Mat& right, FrameEvent* event);
  // Reports every keyframe (oldest first) and its points as marginalised.
  void FlushWindow();
  PointInfo MakePointInfo(const Keyframe& host, const Point& point) const;
  Eigen::Isometry3d ReferenceWorldToCamera() const;
  // DSO's starting activation grid cell: about active_points cells over the image.
  double InitialActivationCell() const;
  // A vignette map of another size than the images: dvso::Error naming the key and the file.
  void RequireVignetteOfImageSize(const PhotometricCalibration& calibration, const std::string& key,
                                  const std::string& file) const;

  OdometryOptions options_;
  StereoCamera camera_;
  OdometryMode mode_;
  ModeCapabilities capabilities_;
  DisparitySource* predictions_ = nullptr;
  PredictionTiming prediction_timing_ = PredictionTiming::kKeyframeAsync;
  int pending_prediction_id_ = -1;  // keyframe whose prediction is still being computed (-1 = none)
  cv::Mat current_left_image_;   // the frame being processed (predictions are asked for it)
  int virtual_stereo_residuals_ = 0;
  double virtual_stereo_energy_ = 0;
  std::unique_ptr<PhotometricCalibration> calibration_;        // left (and right without its own file)
  std::unique_ptr<PhotometricCalibration> right_calibration_;  // right_vignette_file's (null: calibration_)
  std::vector<OdometryObserver*> observers_;

  std::unique_ptr<Window> window_;
  std::vector<KeyframeCandidates> candidates_;
  CoarseTracker tracker_;
  std::unique_ptr<MonoInitializer> mono_init_;
  int mono_init_first_index_ = -1;

  bool initialized_ = false;
  bool finished_ = false;
  int segment_ = 0;
  int num_keyframes_total_ = 0;
  int consecutive_lost_ = 0;
  int frames_since_keyframe_ = 0;
  double first_rmse_ = 0;        // rmse of the first frame tracked against the current reference
  double last_rmse_ = 0;
  double activation_cell_ = 0;   // adaptive activation grid cell (pixels)
  StereoBrightness last_right_brightness_;  // the last stereo keyframe's transfer (reported in FrameEvent)
  bool have_right_brightness_ = false;      // it was refitted from matches: the next keyframe starts from it
  RadialTermPool radial_pool_;              // earlier keyframes' radial fits (a lens property: kept over resets)
  double last_keyframe_radial_ = 0.0;       // the last stereo keyframe's own radial fit (reported in FrameEvent)
  RadialPosition radial_position_;          // rho^2 of a left pixel (the brightness transfer's radial term)
  double selector_block_size_ = 0;  // pixel selector block size that worked for the last keyframe
  int reference_id_ = -1;        // keyframe id the tracker uses
  Eigen::Isometry3d T_last_ref_ = Eigen::Isometry3d::Identity();   // last frame <- reference
  Eigen::Isometry3d velocity_ = Eigen::Isometry3d::Identity();     // last frame <- previous frame
  double last_a_ = 0, last_b_ = 0;                                  // relative to the reference
  Eigen::Isometry3d last_T_world_camera_ = Eigen::Isometry3d::Identity();  // pose of the last reported frame
  Eigen::Isometry3d segment_origin_ = Eigen::Isometry3d::Identity();       // pose given to a new map's first keyframe
  Eigen::Isometry3d mono_second_T_cw_ = Eigen::Isometry3d::Identity();     // mono init: second keyframe pose
  double mono_second_a_ = 0, mono_second_b_ = 0;
};

}  // namespace dvso::vo
