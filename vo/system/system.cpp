// System: per-frame flow (initialisation, tracking, loss handling).
// Keyframe work (window, candidates, activation, marginalisation) is in
// system_keyframes.cpp.
#include "vo/system/system.h"

#include <chrono>

#include "core/disparity_conversion.h"
#include "core/error.h"
#include "vo/frontend/keyframe_decision.h"
#include "vo/optimization/window.h"

namespace dvso::vo {

namespace {
double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

std::string ToString(FrameStatus status) {
  switch (status) {
    case FrameStatus::kTracked: return "tracked";
    case FrameStatus::kKeyframe: return "keyframe";
    case FrameStatus::kInitializing: return "initializing";
    case FrameStatus::kLost: return "lost";
    case FrameStatus::kUnreadable: return "unreadable";
  }
  return "unknown";
}

System::System(const OdometryOptions& options, const StereoCamera& camera, OdometryMode mode,
               DisparitySource* predictions)
    : options_(options),
      camera_(camera),
      mode_(mode),
      capabilities_(CapabilitiesOf(mode)),
      predictions_(predictions),
      prediction_timing_(ParsePredictionTiming(options.dvso.prediction_timing)),
      tracker_(options.tracker),
      radial_position_(camera.left) {
  options_.Check();
  radial_pool_ = RadialTermPool(options_.stereo_brightness.radial_pool_keyframes);
  camera_.left.Check();
  if (capabilities_.has_right_image) Require(camera_.baseline > 0, "stereo odometry needs a baseline > 0");
  if (capabilities_.has_predictions) {
    Require(predictions_ != nullptr, ToString(mode_) + " odometry needs a disparity source (model or files)");
    Require(options_.dvso.virtual_baseline > 0, ToString(mode_) + " odometry needs a virtual baseline > 0");
    // One b_v for the depth initialisation and the eq. 5.8 residual.
    options_.window.virtual_stereo_baseline = options_.dvso.virtual_baseline;
  }
  if (!options_.gamma_file.empty() || !options_.vignette_file.empty()) {
    calibration_ = std::make_unique<PhotometricCalibration>(
        PhotometricCalibration::Load(options_.gamma_file, options_.vignette_file));
    RequireVignetteOfImageSize(*calibration_, "vignette_file", options_.vignette_file);
  }
  if (!options_.right_vignette_file.empty()) {
    Require(capabilities_.has_right_image, "right_vignette_file is for stereo odometry (" + ToString(mode_) +
                                               " odometry reads no right image)");
    right_calibration_ = std::make_unique<PhotometricCalibration>(
        PhotometricCalibration::Load(options_.gamma_file, options_.right_vignette_file));
    RequireVignetteOfImageSize(*right_calibration_, "right_vignette_file", options_.right_vignette_file);
  }
  activation_cell_ = InitialActivationCell();
}

// At the start, not at the first image: a map of another size (another camera's, or one for the
// uncropped sensor) is a configuration error, named by its key.
void System::RequireVignetteOfImageSize(const PhotometricCalibration& calibration, const std::string& key,
                                        const std::string& file) const {
  if (!calibration.has_vignette()) return;
  const cv::Size size = calibration.vignette_size();
  RequireFile(size == cv::Size(camera_.left.width, camera_.left.height), file,
              key + " is " + std::to_string(size.width) + "x" + std::to_string(size.height) + " but the images are " +
                  std::to_string(camera_.left.width) + "x" + std::to_string(camera_.left.height));
}

double System::InitialActivationCell() const {
  return std::sqrt(static_cast<double>(camera_.left.width) * camera_.left.height / options_.active_points);
}

System::~System() = default;

void System::AddObserver(OdometryObserver* observer) {
  Require(observer != nullptr, "System::AddObserver: null observer");
  observers_.push_back(observer);
}

ImagePyramidPtr System::MakePyramid(const cv::Mat& image) const {
  return std::make_shared<ImagePyramid>(image, camera_.left, options_.pyramid, calibration_.get());
}

ImagePyramidPtr System::MakeRightPyramid(const cv::Mat& image) const {
  const PhotometricCalibration* calibration = right_calibration_ ? right_calibration_.get() : calibration_.get();
  return std::make_shared<ImagePyramid>(image, camera_.left, options_.pyramid, calibration);
}

Eigen::Isometry3d System::ReferenceWorldToCamera() const {
  const Keyframe* ref = window_ ? window_->FindKeyframe(reference_id_) : nullptr;
  Require(ref != nullptr, "System: tracking reference keyframe missing");
  return ref->world_to_camera;
}

FrameEvent System::ProcessFrame(int frame_index, double timestamp, const cv::Mat& left, const cv::Mat& right) {
  Require(!finished_, "System::ProcessFrame after Finish");
  if (capabilities_.has_right_image) {
    Require(!right.empty(), "stereo odometry: frame " + std::to_string(frame_index) + " has no right image");
  }
  const auto start = std::chrono::steady_clock::now();
  current_left_image_ = left;
  if (capabilities_.has_predictions) {
    // Speculative: a source with a worker starts on this frame while it is
    // tracked; only a keyframe asks for the result.
    if (prediction_timing_ == PredictionTiming::kSpeculative) predictions_->Prefetch(frame_index, left);
    // Keyframe-async: the last keyframe's prediction may have arrived; its
    // candidates are then traced from this frame on.
    if (initialized_) AttachPendingPrediction(/*wait=*/false);
  }
  FrameEvent ev;
  ev.frame_index = frame_index;
  ev.timestamp = timestamp;
  const ImagePyramidPtr pyr = MakePyramid(left);

  if (!initialized_) {
    if (capabilities_.StartsMetric()) {
      InitializeMetric(frame_index, pyr, right, last_T_world_camera_);
      ev.status = FrameStatus::kKeyframe;
      ev.reference_frame_index = frame_index;
      ev.T_world_camera = last_T_world_camera_;
    } else if (StepMonoInitialization(frame_index, pyr)) {
      // The frame became the second keyframe of the new map.
      MakeKeyframe(frame_index, pyr, cv::Mat(), mono_second_T_cw_, mono_second_a_, mono_second_b_, &ev);
      ev.status = FrameStatus::kKeyframe;
      ev.reference_frame_index = frame_index;
      ev.T_world_camera = window_->CameraToWorld(frame_index);
    } else {
      ev.status = FrameStatus::kInitializing;
      ev.reference_frame_index = mono_init_first_index_;
      ev.T_ref_frame = mono_init_->T_last_first().inverse();
      ev.T_world_camera = segment_origin_ * ev.T_ref_frame;
    }
  } else {
    TrackFrame(frame_index, pyr, right, &ev);
  }
  ev.segment = segment_;
  ev.track_ms = ev.track_ms > 0 ? ev.track_ms : MsSince(start);
  ev.total_ms = MsSince(start);
  if (window_) {
    ev.window_keyframes = window_->num_keyframes();
    ev.active_points = window_->num_points();
  }
  for (const auto& c : candidates_) ev.immature_points += static_cast<int>(c.points.size());
  ev.virtual_stereo_residuals = virtual_stereo_residuals_;
  ev.virtual_stereo_energy = virtual_stereo_energy_;
  ReportStereoBrightness(&ev);
  current_left_image_.release();
  last_T_world_camera_ = ev.T_world_camera;
  for (OdometryObserver* o : observers_) o->OnFrameTracked(ev);
  return ev;
}

void System::ReportStereoBrightness(FrameEvent* ev) const {
  ev->stereo_gain = last_right_brightness_.gain;
  ev->stereo_bias = last_right_brightness_.bias;
  ev->stereo_radial = last_right_brightness_.radial;
  ev->stereo_radial_keyframe = last_keyframe_radial_;
}

FrameEvent System::ReportUnreadableFrame(int frame_index, double timestamp) {
  Require(!finished_, "System::ReportUnreadableFrame after Finish");
  FrameEvent ev;
  ev.frame_index = frame_index;
  ev.timestamp = timestamp;
  ev.status = FrameStatus::kUnreadable;
  ev.segment = segment_;
  ev.T_world_camera = last_T_world_camera_;  // nothing better is known; tracking goes on from the next frame
  if (window_) {
    ev.window_keyframes = window_->num_keyframes();
    ev.active_points = window_->num_points();
  }
  ReportStereoBrightness(&ev);
  for (OdometryObserver* o : observers_) o->OnFrameTracked(ev);
  return ev;
}

void System::TrackFrame(int frame_index, const ImagePyramidPtr& pyr, const cv::Mat& right, FrameEvent* ev) {
  const auto start = std::chrono::steady_clock::now();
  const auto guesses = CoarseTracker::MotionHypotheses(T_last_ref_, velocity_);
  const TrackingResult result = tracker_.TrackWithHypotheses(*pyr, guesses, last_a_, last_b_, last_rmse_);
  ev->track_ms = MsSince(start);
  ev->tracking_rmse = result.rmse;
  ev->hypotheses_tried = result.hypotheses_tried;
  if (!result.success) {
    // Best available pose: constant-velocity prediction from the last frame.
    const Eigen::Isometry3d predicted = last_T_world_camera_ * velocity_.inverse();
    ev->status = FrameStatus::kLost;
    ev->T_world_camera = predicted;
    ++consecutive_lost_;
    Require(options_.reinitialize_on_loss, "tracking lost at frame " + std::to_string(frame_index) +
                                               " (reinitialize_on_loss is off)");
    Require(consecutive_lost_ <= options_.max_consecutive_lost,
            "tracking lost for " + std::to_string(consecutive_lost_) + " consecutive frames");
    ResetAfterLoss(frame_index, predicted);
    if (capabilities_.StartsMetric()) {
      // Stereo / DVSO re-initialise at once from this frame (metric depth from the pair or the prediction).
      InitializeMetric(frame_index, pyr, right, predicted);
      ev->reference_frame_index = frame_index;
    } else {
      StepMonoInitialization(frame_index, pyr);  // this frame becomes the new first frame
      ev->reference_frame_index = frame_index;
    }
    return;
  }
  consecutive_lost_ = 0;
  velocity_ = Orthonormalized(result.T_new_ref * T_last_ref_.inverse());
  T_last_ref_ = result.T_new_ref;
  last_a_ = result.affine_a;
  last_b_ = result.affine_b;
  if (first_rmse_ <= 0) first_rmse_ = result.rmse;
  last_rmse_ = result.rmse;

  const Keyframe* ref = window_->FindKeyframe(reference_id_);
  const Eigen::Isometry3d T_new_cw = Orthonormalized(result.T_new_ref * ref->world_to_camera);
  // Absolute affine parameters (window convention I_j - b_j = e^{a_j - a_i} (I_i - b_i))
  // from the tracker's relative transfer I_new = e^{a} I_ref + b.
  const double a_new = ref->a + result.affine_a;
  const double b_new = result.affine_b + std::exp(result.affine_a) * ref->b;
  TraceCandidates(TraceTarget{pyr.get(), T_new_cw, a_new, b_new});
  ++frames_since_keyframe_;

  ev->status = FrameStatus::kTracked;
  ev->reference_frame_index = reference_id_;
  ev->T_ref_frame = result.T_new_ref.inverse();
  ev->T_world_camera = T_new_cw.inverse();

  KeyframeDecisionInput decision;
  decision.tracking = &result;
  decision.image_width = camera_.left.width;
  decision.image_height = camera_.left.height;
  decision.first_rmse = first_rmse_;
  decision.frames_since_keyframe = frames_since_keyframe_;
  ev->keyframe_score = KeyframeScore(decision, options_.keyframe);
  ev->rmse_ratio = first_rmse_ > 0 ? result.rmse / first_rmse_ : 0;
  if (NeedKeyframe(decision, options_.keyframe)) {
    MakeKeyframe(frame_index, pyr, right, T_new_cw, a_new, b_new, ev);
    ev->status = FrameStatus::kKeyframe;
    ev->reference_frame_index = frame_index;
    ev->T_ref_frame = Eigen::Isometry3d::Identity();
    ev->T_world_camera = window_->CameraToWorld(frame_index);
  }
}

System::KeyframePrediction System::FetchPrediction(int frame_index, const cv::Mat& image) {
  DisparityPair pair = predictions_->Predict(frame_index, image);
  const auto check = [&](const cv::Mat& map, const char* which) {
    Require(map.type() == CV_32FC1 && map.cols == camera_.left.width && map.rows == camera_.left.height,
            std::string("disparity source: ") + which + " map of frame " + std::to_string(frame_index) +
                " is not a CV_32F map of the image size");
  };
  check(pair.left, "left");
  check(pair.right, "right");
  // NaN / zero / negative predictions become "no depth here".
  return KeyframePrediction{SanitizeDisparity(pair.left), SanitizeDisparity(pair.right)};
}

void System::AttachPendingPrediction(bool wait, const TraceTarget* late_trace) {
  if (pending_prediction_id_ < 0) return;
  const int id = pending_prediction_id_;
  if (!wait && !predictions_->IsReady(id)) return;
  pending_prediction_id_ = -1;
  // The request (with its image) was made when the keyframe was created.
  const KeyframePrediction prediction = FetchPrediction(id, cv::Mat());
  const Keyframe* keyframe = window_ ? window_->FindKeyframe(id) : nullptr;
  if (keyframe == nullptr) return;  // already marginalised: nothing to attach to
  window_->SetRightDisparity(id, prediction.right);
  AddCandidates(id, *keyframe->left, nullptr, StereoBrightness{}, &prediction, /*converged=*/false);
  if (late_trace != nullptr && !candidates_.empty() && candidates_.back().keyframe_id == id) {
    TraceCandidateSet(&candidates_.back(), *late_trace);
  }
}

void System::InitializeMetric(int frame_index, const ImagePyramidPtr& left, const cv::Mat& right,
                              const Eigen::Isometry3d& T_world_camera) {
  window_ = std::make_unique<Window>(options_.window, camera_);
  candidates_.clear();
  KeyframeInput input;
  input.id = frame_index;
  input.world_to_camera = T_world_camera.inverse();
  input.left = left;
  KeyframePrediction prediction;
  if (capabilities_.has_right_image) {
    input.right = MakeRightPyramid(right);
    input.right_brightness = StartingStereoBrightness(*left, *input.right);
  }
  if (capabilities_.has_predictions) {
    prediction = FetchPrediction(frame_index, current_left_image_);  // a new map needs its depths now
    input.right_disparity = prediction.right;
  }
  window_->AddKeyframe(input);
  AddCandidates(frame_index, *left, input.right.get(), input.right_brightness,
                capabilities_.has_predictions ? &prediction : nullptr,
                /*converged=*/true);
  // The first keyframe's candidates are activated at once with metric depth:
  // from the static stereo match (Stereo DSO) or the prediction (DVSO "in").
  ActivateCandidates(frame_index, /*include_new_keyframe=*/true);
  // A lone keyframe's points only have residuals through a stereo term
  // (static or virtual); without one there is nothing to optimise, and the
  // outlier pass would drop every point for having no residual.
  bool any_residual = false;
  for (const Point& p : window_->keyframe(0).points) any_residual = any_residual || !p.residuals.empty();
  if (any_residual) {
    FrameEvent unused;
    RunOptimization(&unused);
  }
  ++num_keyframes_total_;
  SetTrackingReference(frame_index);
  initialized_ = true;
  EmitWindowEvent(frame_index);
}

bool System::StepMonoInitialization(int frame_index, const ImagePyramidPtr& left) {
  if (!mono_init_ || !mono_init_->has_first_frame() || mono_init_->failed()) {
    mono_init_ = std::make_unique<MonoInitializer>(options_.mono_init, options_.selector, options_.tracker);
    mono_init_->SetFirstFrame(left);
    mono_init_first_index_ = frame_index;
    segment_origin_ = last_T_world_camera_;
    return false;
  }
  if (!mono_init_->AddFrame(*left)) {
    if (mono_init_->failed()) {
      // Start over with this frame as the first one.
      const Eigen::Isometry3d pose = segment_origin_ * mono_init_->T_last_first().inverse();
      mono_init_->SetFirstFrame(left);
      mono_init_first_index_ = frame_index;
      segment_origin_ = pose;
    }
    return false;
  }
  const MonoInitialization& r = mono_init_->result();
  window_ = std::make_unique<Window>(options_.window, camera_);
  candidates_.clear();
  KeyframeInput input;
  input.id = mono_init_first_index_;
  input.world_to_camera = segment_origin_.inverse();
  input.left = mono_init_->first_frame();
  window_->AddKeyframe(input);
  for (const ReferencePoint& p : r.points) window_->AddPoint(input.id, p.u, p.v, p.idepth);
  ++num_keyframes_total_;
  mono_second_T_cw_ = r.T_last_first * input.world_to_camera;
  mono_second_a_ = r.affine_a;
  mono_second_b_ = r.affine_b;
  initialized_ = true;
  mono_init_.reset();
  return true;
}

void System::ResetAfterLoss(int frame_index, const Eigen::Isometry3d& predicted) {
  FlushWindow();
  for (OdometryObserver* o : observers_) o->OnReset(frame_index);
  window_.reset();
  candidates_.clear();
  tracker_ = CoarseTracker(options_.tracker);
  mono_init_.reset();
  if (pending_prediction_id_ >= 0) {
    // Its keyframe is gone, but the request is still collected: a failing model must fail the run here too
    // (its error would otherwise vanish with the worker's result).
    FetchPrediction(pending_prediction_id_, cv::Mat());
    pending_prediction_id_ = -1;
  }
  // The activation grid and selector block adapted to the lost map's point count; a new map starts as the
  // first one did (a grid grown to its 100 px cap would give the new first keyframe a few dozen points).
  activation_cell_ = InitialActivationCell();
  selector_block_size_ = 0;
  // A wrong transfer may have caused the loss: the new map's first keyframe starts from the quantiles.
  have_right_brightness_ = false;
  initialized_ = false;
  ++segment_;
  reference_id_ = -1;
  T_last_ref_ = velocity_ = Eigen::Isometry3d::Identity();
  last_a_ = last_b_ = first_rmse_ = last_rmse_ = 0;
  frames_since_keyframe_ = 0;
  virtual_stereo_residuals_ = 0;  // they described the window just dropped
  virtual_stereo_energy_ = 0;
  last_T_world_camera_ = predicted;
  segment_origin_ = predicted;
}

void System::Finish() {
  if (finished_) return;
  finished_ = true;
  // The last keyframe's keyframe-async prediction is collected too: a failing model must fail the run
  // (its error would otherwise be dropped with the worker's result), and every request gets its answer.
  AttachPendingPrediction(/*wait=*/true);
  FlushWindow();
  for (OdometryObserver* o : observers_) o->OnFinished();
}

}  // namespace dvso::vo
