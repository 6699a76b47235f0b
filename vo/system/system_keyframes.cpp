// System: keyframe work — window insertion, candidate (immature) points,
// activation, windowed optimisation, marginalisation and window events.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "core/disparity_conversion.h"
#include "core/error.h"
#include "vo/frontend/pixel_selector.h"
#include "vo/system/system.h"

namespace dvso::vo {

namespace {

// Pixel-to-pixel mapping host -> target at level 0: p_t ~ KRKi p_h + Kt idepth.
struct PixelTransfer {
  Eigen::Matrix3f KRKi;
  Eigen::Vector3f Kt;
};

PixelTransfer MakeTransfer(const PinholeCamera& cam, const Eigen::Isometry3d& T_target_host) {
  const Eigen::Matrix3d K = cam.K();
  PixelTransfer t;
  t.KRKi = (K * T_target_host.linear() * K.inverse()).cast<float>();
  t.Kt = (K * T_target_host.translation()).cast<float>();
  return t;
}

}  // namespace

void System::MakeKeyframe(int frame_index, const ImagePyramidPtr& left, const cv::Mat& right,
                          const Eigen::Isometry3d& T_cw, double a, double b, FrameEvent* event) {
  ImagePyramidPtr right_pyr;
  StereoBrightness right_brightness;
  if (capabilities_.has_right_image && !right.empty()) {
    right_pyr = MakeRightPyramid(right);
    right_brightness = StartingStereoBrightness(*left, *right_pyr);
  }
  KeyframePrediction prediction;  // stays empty while a keyframe-async prediction is pending
  if (capabilities_.has_predictions) {
    if (prediction_timing_ == PredictionTiming::kKeyframeAsync) {
      // At most one prediction outstanding: the previous keyframe's comes
      // first; its candidates are traced against this (tracked) frame.
      const TraceTarget this_frame{left.get(), T_cw, a, b};
      AttachPendingPrediction(/*wait=*/true, &this_frame);
      predictions_->Prefetch(frame_index, current_left_image_);
      if (predictions_->IsReady(frame_index)) {
        prediction = FetchPrediction(frame_index, current_left_image_);
      } else {
        pending_prediction_id_ = frame_index;  // D^R and candidates follow when it arrives
      }
    } else {
      prediction = FetchPrediction(frame_index, current_left_image_);
    }
  }
  const bool have_prediction = !prediction.left.empty();
  KeyframeInput input;
  input.id = frame_index;
  input.world_to_camera = T_cw;
  input.a = a;
  input.b = b;
  input.left = left;
  input.right = right_pyr;
  input.right_brightness = right_brightness;
  input.right_disparity = prediction.right;  // empty outside DVSO: no virtual stereo residuals
  window_->AddKeyframe(input);
  ActivateCandidates(frame_index, /*include_new_keyframe=*/false);
  RunOptimization(event);
  MarginalizeKeyframes();
  if (!capabilities_.has_predictions || have_prediction) {
    AddCandidates(frame_index, *left, right_pyr.get(), right_brightness, have_prediction ? &prediction : nullptr,
                  /*converged=*/false);
  }
  ++num_keyframes_total_;
  SetTrackingReference(frame_index);
  EmitWindowEvent(frame_index);
}

void System::TraceCandidates(const TraceTarget& target) {
  for (KeyframeCandidates& c : candidates_) TraceCandidateSet(&c, target);
}

void System::TraceCandidateSet(KeyframeCandidates* candidates, const TraceTarget& target) {
  const Keyframe* host = window_->FindKeyframe(candidates->keyframe_id);
  if (host == nullptr) return;
  const PixelTransfer tr = MakeTransfer(camera_.left, target.T_frame_w * host->world_to_camera.inverse());
  const float ratio = static_cast<float>(std::exp(target.a - host->a));
  const float offset = static_cast<float>(target.b - ratio * host->b);
  for (ImmaturePoint& p : candidates->points) {
    p.Trace(target.frame->level(0), tr.KRKi, tr.Kt, ratio, offset, options_.immature);
  }
}

StereoBrightness System::StartingStereoBrightness(const ImagePyramid& left, const ImagePyramid& right) const {
  // The previous stereo keyframe's refitted transfer (the same rig, a similar exposure);
  // the first keyframe starts from the images' quantiles.
  if (have_right_brightness_) return last_right_brightness_;
  StereoBrightness start = EstimateStereoBrightness(left.level(0), right.level(0), options_.stereo_brightness);
  // The quantiles cannot see a radial term, but the lenses' pooled one (kept over resets) is known. The
  // quantile gain holds the term's mean over the image (rho^2 averages 1/3 over an image centred on the
  // principal point), which the radial factor would otherwise count twice.
  if (options_.stereo_brightness.estimate_radial && radial_pool_.size() > 0) {
    constexpr double kMeanRhoSqOverTheImage = 1.0 / 3.0;  // E[(x^2 + y^2) / ((W^2 + H^2) / 4)], uniform x, y
    start.radial = radial_pool_.Median();
    start.gain /= 1.0 + start.radial * kMeanRhoSqOverTheImage;
  }
  return start;
}

std::vector<ImmaturePoint> System::TraceStaticStereo(const std::vector<ImmaturePoint>& points,
                                                     const ImagePyramid& right,
                                                     const StereoBrightness& transfer) const {
  const Eigen::Vector3f stereo_Kt(static_cast<float>(-camera_.FxB()), 0.f, 0.f);
  const float max_disparity = static_cast<float>(
      std::min(options_.stereo_max_disparity_fraction * camera_.left.width, options_.stereo_max_disparity_px));
  std::vector<ImmaturePoint> traced;
  traced.reserve(points.size());
  for (ImmaturePoint p : points) {
    // Static stereo, through the pair's brightness transfer I_right ~ Gain(rho^2) * I_left + bias.
    const TraceStatus s = p.Trace(right.level(0), Eigen::Matrix3f::Identity(), stereo_Kt,
                                  static_cast<float>(transfer.Gain(radial_position_.Sq(p.u, p.v))),
                                  static_cast<float>(transfer.bias), options_.immature, max_disparity);
    if (s == TraceStatus::kOutOfBounds) continue;
    if (s != TraceStatus::kGood) {
      // No usable stereo match: keep it as a plain candidate for temporal tracing.
      p.idepth_min = 0;
      p.idepth_max = std::numeric_limits<float>::infinity();
      p.last_status = TraceStatus::kUninitialized;
      p.quality = 10000.f;
    }
    traced.push_back(p);
  }
  return traced;
}

std::optional<System::MatchedBrightnessFit> System::FitStereoBrightnessFromMatches(
    const std::vector<ImmaturePoint>& traced, const ImagePyramid& left, const ImagePyramid& right,
    const UnclippedRange& left_unclipped, const UnclippedRange& right_unclipped) const {
  const StereoBrightnessOptions& o = options_.stereo_brightness;
  const PyramidLevel& host = left.level(0);
  const PyramidLevel& target = right.level(0);
  const float fxb = static_cast<float>(camera_.FxB());
  std::vector<double> host_intensity, right_intensity, host_rho_sq;
  int matched_points = 0;
  for (const ImmaturePoint& p : traced) {
    // Unambiguous matches only (DSO's activation quality): a repeated texture's wrong match would
    // compare unrelated pixels. An interval clamped at inverse depth 0 (disparity below the search's
    // error) is not centred on the match, so its midpoint is not the matched position.
    if (p.last_status != TraceStatus::kGood || !p.ReadyForActivation(options_.immature) || !(p.idepth_min > 0)) {
      continue;
    }
    const float x = p.u - fxb * p.IdepthEstimate();
    // Both images are read half a sub-pixel step off: bilinear interpolation at a fraction t
    // averages neighbours with weight t (1 - t), and reading only the right image between pixels
    // would smooth it alone. Candidates sit at intensity extremes (high gradient), so the smoothed
    // side regresses towards the local mean and the fit finds gain < 1 with identical cameras
    // (0.985, bias +0.6 on a simulated world before this). Read at x - f/2 and u - f/2 (f = frac x),
    // the two fractions are f/2 and 1 - f/2: the same amount of smoothing on both sides.
    const float half_fraction = 0.5f * (x - std::floor(x));
    const float xr = x - half_fraction, xl = p.u - half_fraction;
    if (!target.InBounds(xr, p.v, kPatternRadius + 1.5f) || !host.InBounds(xl, p.v, kPatternRadius + 1.5f)) continue;
    ++matched_points;
    for (int k = 0; k < kPatternSize; ++k) {
      const float dx = static_cast<float>(kPatternOffsets[k][0]), dy = static_cast<float>(kPatternOffsets[k][1]);
      const float h = host.InterpolateIntensity(xl + dx, p.v + dy);
      const float r = target.InterpolateIntensity(xr + dx, p.v + dy);
      // Clipped pixels (black or saturated) would all lie on one side of the line.
      if (!left_unclipped.Contains(h) || !right_unclipped.Contains(r)) continue;
      host_intensity.push_back(h);
      right_intensity.push_back(r);
      host_rho_sq.push_back(radial_position_.Sq(p.u + dx, p.v + dy));
    }
  }
  if (matched_points < o.min_matched_points) return std::nullopt;
  std::optional<StereoBrightness> transfer;
  std::optional<double> keyframe_radial;
  if (o.estimate_radial) {
    // The radial term is the lenses' (RadialTermPool): this keyframe's fit pooled with the earlier
    // keyframes' ones, or the pool alone where this keyframe's fit is refused; gain and bias, which
    // auto exposure moves, are this keyframe's own.
    keyframe_radial = FitRadialTerm(host_intensity, right_intensity, host_rho_sq, o.huber_threshold, o.max_radial);
    if (!keyframe_radial && radial_pool_.size() == 0) return std::nullopt;
    const double radial = keyframe_radial ? radial_pool_.MedianWith(*keyframe_radial) : radial_pool_.Median();
    transfer = FitBrightnessTransferAtRadial(host_intensity, right_intensity, host_rho_sq, radial, o.huber_threshold,
                                             o.max_gain_ratio);
  } else {
    transfer = FitBrightnessTransfer(host_intensity, right_intensity, o.huber_threshold, o.max_gain_ratio);
  }
  if (!transfer) return std::nullopt;
  // The intensity range the fit speaks for: 2nd to 98th percentile of the left samples.
  std::vector<double> sorted = host_intensity;
  const size_t i_lo = sorted.size() / 50, i_hi = sorted.size() - 1 - sorted.size() / 50;
  std::nth_element(sorted.begin(), sorted.begin() + i_lo, sorted.end());
  const double low = sorted[i_lo];
  std::nth_element(sorted.begin(), sorted.begin() + i_hi, sorted.end());
  return MatchedBrightnessFit{*transfer, low, sorted[i_hi], keyframe_radial};
}

std::vector<ImmaturePoint> System::MatchStaticStereo(int keyframe_id, std::vector<ImmaturePoint> points,
                                                     const ImagePyramid& left, const ImagePyramid& right,
                                                     const StereoBrightness& start) {
  const StereoBrightnessOptions& o = options_.stereo_brightness;
  StereoBrightness transfer = start;
  bool refitted = false;
  std::optional<double> keyframe_radial;  // the last refit's own radial term
  std::vector<ImmaturePoint> traced = TraceStaticStereo(points, right, transfer);
  if (o.estimate && o.max_matching_passes > 1) {
    const UnclippedRange left_unclipped = UnclippedIntensityRange(left.level(0));
    const UnclippedRange right_unclipped = UnclippedIntensityRange(right.level(0));
    // Refit from the matches; match again with the refitted transfer while it moves.
    for (int pass = 1; pass < o.max_matching_passes; ++pass) {
      const std::optional<MatchedBrightnessFit> fit =
          FitStereoBrightnessFromMatches(traced, left, right, left_unclipped, right_unclipped);
      if (!fit) break;  // too few matches or no plausible line: this keyframe keeps its start
      const double change = BrightnessTransferChange(transfer, fit->transfer, fit->low, fit->high);
      transfer = fit->transfer;
      refitted = true;
      keyframe_radial = fit->keyframe_radial;
      if (change <= o.rematch_change) break;
      traced = TraceStaticStereo(points, right, transfer);
    }
  }
  // Only a transfer confirmed by matches is the next keyframe's start; otherwise it starts from the quantiles
  // again (a wrong start would otherwise be handed on from keyframe to keyframe).
  last_right_brightness_ = transfer;
  have_right_brightness_ = refitted;
  last_keyframe_radial_ = !o.estimate_radial ? 0.0 : keyframe_radial.value_or(std::numeric_limits<double>::quiet_NaN());
  if (keyframe_radial) radial_pool_.Add(*keyframe_radial);
  window_->SetRightBrightness(keyframe_id, transfer);
  return traced;
}

void System::AddCandidates(int keyframe_id, const ImagePyramid& left, const ImagePyramid* right,
                           const StereoBrightness& right_brightness, const KeyframePrediction* prediction,
                           bool converged) {
  KeyframeCandidates c;
  c.keyframe_id = keyframe_id;
  const std::vector<SelectedPixel> pixels = SelectPixels(left, options_.selector, &selector_block_size_);
  c.points.reserve(pixels.size());
  const DvsoOptions& dvso = options_.dvso;
  for (const SelectedPixel& px : pixels) {
    float predicted_idepth = 0.0f;
    if (prediction != nullptr) {
      // DVSO point selection (paper section 4): no point where the prediction
      // has no depth or fails the left-right check (likely occluded).
      if (dvso.left_right_check &&
          LeftRightDisparityError(prediction->left, prediction->right, px.x, px.y) > dvso.left_right_threshold) {
        continue;
      }
      predicted_idepth = static_cast<float>(
          InverseDepthFromDisparity(prediction->left.at<float>(px.y, px.x), camera_.left.fx, dvso.virtual_baseline));
      if (!(predicted_idepth > 0.0f)) continue;
    }
    ImmaturePoint p;
    if (!p.Initialize(left.level(0), keyframe_id, static_cast<float>(px.x), static_cast<float>(px.y), px.level)) {
      continue;
    }
    if (prediction != nullptr) {
      // Depth initialisation "in": d = D^L(p) / (f_x b_v); the epipolar search refines it.
      p.SetPredictedInterval(predicted_idepth, static_cast<float>(dvso.init_relative_range), converged);
    }
    c.points.push_back(p);
  }
  if (right != nullptr) {
    c.points = MatchStaticStereo(keyframe_id, std::move(c.points), left, *right, right_brightness);
  }
  if (right != nullptr && !observers_.empty()) {
    std::vector<PointInfo> matched;
    for (const ImmaturePoint& p : c.points) {
      if (p.last_status != TraceStatus::kGood || !p.ReadyForActivation(options_.immature)) continue;
      PointInfo info;
      info.host_frame_index = keyframe_id;
      info.u = p.u;
      info.v = p.v;
      info.idepth = p.IdepthEstimate();
      matched.push_back(info);
    }
    for (OdometryObserver* o : observers_) o->OnKeyframeCandidates(keyframe_id, matched);
  }
  candidates_.push_back(std::move(c));
}

void System::ActivateCandidates(int new_keyframe_id, bool include_new_keyframe) {
  const Keyframe* newest = window_->FindKeyframe(new_keyframe_id);
  Require(newest != nullptr, "System: new keyframe missing in the window");
  const PinholeCamera& cam = camera_.left;
  const double cell = std::max(options_.min_activation_distance, activation_cell_);
  const int gw = static_cast<int>(std::ceil(cam.width / cell));
  const int gh = static_cast<int>(std::ceil(cam.height / cell));
  std::vector<uint8_t> occupied(static_cast<size_t>(gw) * gh, 0);
  auto cell_of = [&](double u, double v) -> int {
    if (u < 0 || v < 0 || u >= cam.width || v >= cam.height) return -1;
    return static_cast<int>(v / cell) * gw + static_cast<int>(u / cell);
  };
  // Existing active points, projected into the new keyframe, occupy their cells
  // (DSO's distance map: new points only where there are none yet).
  for (int k = 0; k < window_->num_keyframes(); ++k) {
    const Keyframe& kf = window_->keyframe(k);
    const Eigen::Isometry3d T_new_host = newest->world_to_camera * kf.world_to_camera.inverse();
    for (const Point& p : kf.points) {
      const Eigen::Vector3d X = T_new_host * (cam.Unproject(p.u, p.v) / p.idepth);
      if (X.z() <= 0) continue;
      const Eigen::Vector2d uv = cam.Project(X);
      const int c = cell_of(uv.x(), uv.y());
      if (c >= 0) occupied[c] = 1;
    }
  }
  for (KeyframeCandidates& c : candidates_) {
    if (c.keyframe_id == new_keyframe_id && !include_new_keyframe) continue;
    const Keyframe* host = window_->FindKeyframe(c.keyframe_id);
    if (host == nullptr) continue;
    const Eigen::Isometry3d T_new_host = newest->world_to_camera * host->world_to_camera.inverse();
    std::vector<ImmaturePoint> keep;
    keep.reserve(c.points.size());
    for (ImmaturePoint& p : c.points) {
      if (p.last_status == TraceStatus::kOutOfBounds) continue;  // dropped
      if (!p.ReadyForActivation(options_.immature)) {
        keep.push_back(p);
        continue;
      }
      const double idepth = p.IdepthEstimate();
      const Eigen::Vector3d X = T_new_host * (cam.Unproject(p.u, p.v) / idepth);
      if (X.z() <= 0) continue;  // behind the newest camera: useless
      const Eigen::Vector2d uv = cam.Project(X);
      const int cidx = cell_of(uv.x(), uv.y());
      if (cidx < 0) continue;  // left the field of view: drop (DSO drops OOB candidates)
      if (occupied[cidx]) {
        keep.push_back(p);
        continue;
      }
      if (window_->AddPoint(c.keyframe_id, p.u, p.v, idepth) >= 0) occupied[cidx] = 1;
    }
    c.points.swap(keep);
  }
  // Adapt the activation grid so the window holds about active_points points (DSO currentMinActDist).
  const int n = window_->num_points();
  if (n < 0.66 * options_.active_points) activation_cell_ *= 0.8;
  if (n > 1.25 * options_.active_points) activation_cell_ *= 1.2;
  activation_cell_ = std::min(100.0, std::max(options_.min_activation_distance, activation_cell_));
}

void System::RunOptimization(FrameEvent* event) {
  if (!options_.bundle_adjustment || options_.optimization_iterations == 0 || window_->num_points() == 0) {
    UpdateVirtualStereoStatistics();  // run_log.csv describes this window even when it is not optimised
    return;
  }
  const auto start = std::chrono::steady_clock::now();
  window_->Optimize(options_.optimization_iterations);
  // Points the new keyframe no longer sees leave the window (DSO), so that
  // keyframes whose points are gone get marginalised.
  ReportMarginalizedPoints(window_->MarginalizeInvisiblePoints());
  window_->RemoveOutliers();
  UpdateVirtualStereoStatistics();
  event->optimize_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

void System::UpdateVirtualStereoStatistics() {
  virtual_stereo_residuals_ = 0;
  virtual_stereo_energy_ = 0;
  for (int k = 0; k < window_->num_keyframes(); ++k) {
    for (const Point& p : window_->keyframe(k).points) {
      for (const Residual& r : p.residuals) {
        if (r.kind != ResidualKind::kVirtualStereo || r.state != ResidualState::kActive) continue;
        ++virtual_stereo_residuals_;
        virtual_stereo_energy_ += r.energy;
      }
    }
  }
}

PointInfo System::MakePointInfo(const Keyframe& host, const Point& point) const {
  PointInfo info;
  info.host_frame_index = host.id;
  info.u = point.u;
  info.v = point.v;
  info.idepth = point.idepth;
  info.world = host.world_to_camera.inverse() * (camera_.left.Unproject(point.u, point.v) / point.idepth);
  info.num_residuals = static_cast<int>(point.residuals.size());
  info.idepth_hessian = point.idepth_hessian;
  info.stereo_energy = StaticStereoEnergy(point);
  int active = 0;
  double energy = 0;
  for (const Residual& r : point.residuals) {
    if (r.state != ResidualState::kActive) continue;
    ++active;
    energy += r.energy;
    if (r.kind == ResidualKind::kTemporal) ++info.num_good_residuals;
  }
  info.mean_energy = active > 0 ? static_cast<float>(energy / active) : 0.f;
  return info;
}

void System::ReportMarginalizedPoints(const std::vector<MarginalizedPoint>& leaving) const {
  if (observers_.empty() || leaving.empty()) return;
  std::vector<PointInfo> points;
  points.reserve(leaving.size());
  for (const MarginalizedPoint& m : leaving) {
    PointInfo p;
    p.host_frame_index = m.host_id;
    p.u = m.u;
    p.v = m.v;
    p.idepth = m.idepth;
    p.world = m.world;
    p.num_good_residuals = m.num_residuals;
    p.num_residuals = m.num_residuals;
    p.idepth_hessian = m.idepth_hessian;
    p.mean_energy = m.mean_energy;
    p.stereo_energy = m.stereo_energy;
    points.push_back(p);
  }
  for (OdometryObserver* o : observers_) o->OnPointsMarginalized(points);
}

void System::MarginalizeKeyframes() {
  for (int id : window_->KeyframesToMarginalize()) {
    const Keyframe* kf = window_->FindKeyframe(id);
    if (kf == nullptr) continue;
    const KeyframeInfo info{id, kf->world_to_camera.inverse(), kf->a, kf->b};
    ReportMarginalizedPoints(window_->MarginalizeKeyframe(id));
    for (OdometryObserver* o : observers_) o->OnKeyframeMarginalized(info);
    candidates_.erase(std::remove_if(candidates_.begin(), candidates_.end(),
                                     [id](const KeyframeCandidates& c) { return c.keyframe_id == id; }),
                      candidates_.end());
  }
}

void System::SetTrackingReference(int keyframe_id) {
  const Keyframe* ref = window_->FindKeyframe(keyframe_id);
  Require(ref != nullptr, "System: reference keyframe missing");
  const PinholeCamera& cam = camera_.left;
  std::vector<ReferencePoint> points;
  points.reserve(window_->num_points());
  for (int k = 0; k < window_->num_keyframes(); ++k) {
    const Keyframe& kf = window_->keyframe(k);
    const Eigen::Isometry3d T_ref_host = ref->world_to_camera * kf.world_to_camera.inverse();
    for (const Point& p : kf.points) {
      const Eigen::Vector3d X = T_ref_host * (cam.Unproject(p.u, p.v) / p.idepth);
      if (X.z() <= 1e-3) continue;
      const Eigen::Vector2d uv = cam.Project(X);
      if (!cam.InImage(uv.x(), uv.y(), 2.0)) continue;
      points.push_back({static_cast<float>(uv.x()), static_cast<float>(uv.y()), static_cast<float>(1.0 / X.z())});
    }
  }
  tracker_.SetReference(ref->left, points);
  reference_id_ = keyframe_id;
  T_last_ref_ = Eigen::Isometry3d::Identity();
  last_a_ = last_b_ = 0;
  first_rmse_ = 0;  // last_rmse_ is kept: residual levels are comparable across references
  frames_since_keyframe_ = 0;
}

void System::EmitWindowEvent(int frame_index) {
  if (observers_.empty()) return;
  WindowEvent ev;
  ev.frame_index = frame_index;
  for (int k = 0; k < window_->num_keyframes(); ++k) {
    const Keyframe& kf = window_->keyframe(k);
    ev.keyframes.push_back({kf.id, kf.world_to_camera.inverse(), kf.a, kf.b});
    for (const Point& p : kf.points) ev.points.push_back(MakePointInfo(kf, p));
  }
  for (OdometryObserver* o : observers_) o->OnWindowOptimized(ev);
}

void System::FlushWindow() {
  if (!window_) return;
  for (int k = 0; k < window_->num_keyframes(); ++k) {
    const Keyframe& kf = window_->keyframe(k);
    if (!observers_.empty()) {
      std::vector<PointInfo> points;
      for (const Point& p : kf.points) points.push_back(MakePointInfo(kf, p));
      const KeyframeInfo info{kf.id, kf.world_to_camera.inverse(), kf.a, kf.b};
      for (OdometryObserver* o : observers_) o->OnPointsMarginalized(points);
      for (OdometryObserver* o : observers_) o->OnKeyframeMarginalized(info);
    }
  }
}

}  // namespace dvso::vo
