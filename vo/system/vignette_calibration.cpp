#include "vo/system/vignette_calibration.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/plot.h"
#include "core/progress.h"
#include "vo/frame/image_pyramid.h"
#include "vo/frame/photometric_calibration.h"
#include "vo/system/observer.h"

namespace dvso::vo {

void VignetteCalibrationOptions::Check() const {
  Require(neighbour_keyframes >= 1, "calibrate-vignette: --neighbour-keyframes must be >= 1");
  Require(blur_fraction >= 0 && blur_fraction <= 0.1, "calibrate-vignette: --blur-fraction must be in [0, 0.1]");
  Require(border >= 2, "calibrate-vignette: border must be >= 2 (the slope is a central difference around a point)");
  Require(max_sample_gradient >= 0, "calibrate-vignette: --max-sample-gradient must be >= 0");
  Require(min_intensity < max_intensity, "calibrate-vignette: min_intensity must be below max_intensity");
  Require(max_points >= 1, "calibrate-vignette: max_points must be >= 1");
  Require(min_good_residuals >= 0, "calibrate-vignette: min_good_residuals must be >= 0");
  fit.Check();
}

namespace {

// A marginalised point, kept until its host keyframe's final pose is known.
struct HostedPoint {
  int host_frame_index;
  float u, v;
  double idepth;
};

struct FinalKeyframe {
  int frame_index;
  Eigen::Isometry3d T_world_camera;
  int segment;
};

// Collects what the fit needs from the odometry's events: the marginalised points that were well
// constrained and every keyframe's final pose with its tracking segment.
class VignetteSampleCollector : public OdometryObserver {
 public:
  explicit VignetteSampleCollector(int min_good_residuals) : min_good_residuals_(min_good_residuals) {}
  void OnPointsMarginalized(const std::vector<PointInfo>& points) override {
    for (const PointInfo& p : points) {
      if (p.num_good_residuals < min_good_residuals_ || !(p.idepth > 0)) continue;
      points_.push_back({p.host_frame_index, p.u, p.v, p.idepth});
    }
  }
  void OnKeyframeMarginalized(const KeyframeInfo& keyframe) override {
    keyframes_.push_back({keyframe.frame_index, keyframe.T_world_camera, segment_});
  }
  void OnReset(int /*frame_index*/) override { ++segment_; }

  const std::vector<HostedPoint>& points() const { return points_; }
  const std::vector<FinalKeyframe>& keyframes() const { return keyframes_; }
  int segments() const { return segment_ + 1; }

 private:
  int min_good_residuals_;
  int segment_ = 0;
  std::vector<HostedPoint> points_;
  std::vector<FinalKeyframe> keyframes_;
};

}  // namespace

VignetteCalibration CalibrateVignette(const SequenceReader& sequence, const OdometryOptions& options,
                                      OdometryMode mode, const std::string& out_dir, const SequenceRunOptions& run,
                                      const VignetteCalibrationOptions& calibration) {
  calibration.Check();
  Require(options.vignette_file.empty() && options.right_vignette_file.empty(),
          "calibrate-vignette estimates the vignette of the raw images: leave vignette_file and "
          "right_vignette_file out of the config");
  Require(!CapabilitiesOf(mode).has_predictions, "calibrate-vignette runs mono or stereo odometry");
  VignetteSampleCollector collector(calibration.min_good_residuals);
  SequenceRunOptions run_with_collector = run;
  run_with_collector.extra_observers.push_back(&collector);
  VignetteCalibration result;
  result.run = RunOdometryOnSequence(sequence, options, mode, out_dir, run_with_collector);
  result.camera = sequence.camera().left;
  result.segments = collector.segments();

  // Keyframes in frame order (DSO marginalises them out of order); a point's host is found by frame index.
  // Only the longest tracking segment is used: segments share no points, so each would carry its own
  // exposure scale (a_f R_p), which the fit fixes once (a_0 = 1).
  Require(!collector.keyframes().empty(), "calibrate-vignette: the odometry made no keyframe");
  std::map<int, int> keyframes_per_segment;
  for (const FinalKeyframe& k : collector.keyframes()) ++keyframes_per_segment[k.segment];
  const int longest_segment =
      std::max_element(keyframes_per_segment.begin(), keyframes_per_segment.end(),
                       [](const auto& a, const auto& b) { return a.second < b.second; })->first;
  std::vector<FinalKeyframe> keyframes;
  for (const FinalKeyframe& k : collector.keyframes())
    if (k.segment == longest_segment) keyframes.push_back(k);
  std::sort(keyframes.begin(), keyframes.end(),
            [](const FinalKeyframe& a, const FinalKeyframe& b) { return a.frame_index < b.frame_index; });
  std::map<int, int> position_of_frame;
  for (int i = 0; i < static_cast<int>(keyframes.size()); ++i) position_of_frame[keyframes[i].frame_index] = i;
  Require(keyframes.size() >= 2, "calibrate-vignette: the odometry made fewer than 2 keyframes in one segment");

  // World points, bucketed by their host's position; thinned evenly to max_points.
  const PinholeCamera& camera = result.camera;
  const std::vector<HostedPoint>& hosted = collector.points();
  const size_t stride = std::max<size_t>(1, (hosted.size() + calibration.max_points - 1) / calibration.max_points);
  std::vector<std::vector<std::pair<int, Eigen::Vector3d>>> points_of_host(keyframes.size());
  int num_points = 0;
  for (size_t i = 0; i < hosted.size(); i += stride) {
    const HostedPoint& p = hosted[i];
    const auto it = position_of_frame.find(p.host_frame_index);
    if (it == position_of_frame.end()) continue;
    const Eigen::Vector3d world = keyframes[it->second].T_world_camera * (camera.Unproject(p.u, p.v) / p.idepth);
    points_of_host[it->second].emplace_back(num_points++, world);
  }
  Require(num_points > 0, "calibrate-vignette: the odometry marginalised no usable point");

  // Sample every point in the keyframes around its host (same segment), image by image.
  const PhotometricCalibration response = PhotometricCalibration::Load(options.gamma_file, "");
  const RadialPosition rho(camera);
  const double blur_sigma = calibration.blur_fraction * camera.width;
  const int n = calibration.neighbour_keyframes, K = static_cast<int>(keyframes.size());
  std::vector<VignetteObservation> observations;
  SequenceReadOptions read;
  read.load_right = false;
  // One pyramid level: the odometry's bilinear (I, dI/dx, dI/dy) of the blurred image, its slope included.
  ImagePyramidOptions one_level;
  one_level.max_levels = 1;
  std::unique_ptr<ProgressBar> bar;
  if (run.progress) bar = std::make_unique<ProgressBar>("sampling keyframes", K);
  for (int j = 0; j < K; ++j) {
    cv::Mat image = response.Correct(sequence.Read(keyframes[j].frame_index, read).left);
    if (blur_sigma > 0) cv::GaussianBlur(image, image, cv::Size(0, 0), blur_sigma);
    const ImagePyramid pyramid(image, camera, one_level);
    const PyramidLevel& level = pyramid.level(0);
    const Eigen::Isometry3d T_camera_world = keyframes[j].T_world_camera.inverse();
    for (int h = std::max(0, j - n); h <= std::min(K - 1, j + n); ++h) {
      for (const auto& [id, world] : points_of_host[h]) {
        const Eigen::Vector3d X = T_camera_world * world;
        if (X.z() <= 1e-3) continue;
        const Eigen::Vector2d uv = camera.Project(X);
        if (!camera.InImage(uv.x(), uv.y(), calibration.border)) continue;
        const Eigen::Vector3f sample = level.Interpolate(static_cast<float>(uv.x()), static_cast<float>(uv.y()));
        const float intensity = sample[0];
        if (calibration.max_sample_gradient > 0 && sample.tail<2>().norm() > calibration.max_sample_gradient) continue;
        if (intensity < calibration.min_intensity || intensity > calibration.max_intensity) continue;
        observations.push_back({id, j, rho.Sq(uv.x(), uv.y()), intensity});
      }
    }
    if (bar) bar->Update(j + 1, std::to_string(observations.size()) + " samples");
  }
  if (bar) bar->Finish();
  result.keyframes = K;
  result.fit = FitVignette(observations, num_points, K, calibration.fit);
  return result;
}

void WriteVignetteCalibration(const std::string& out_dir, const VignetteCalibration& c) {
  EnsureDirectory(out_dir);
  c.fit.vignette.WritePng(JoinPath(out_dir, "vignette.png"), c.camera);
  const cv::Mat v = c.fit.vignette.Image(c.camera);
  double min_v = 0;
  cv::minMaxLoc(v, &min_v, nullptr);
  WriteStreamAtomically(JoinPath(out_dir, "vignette_fit.yaml"), [&](std::ostream& out) {
    out << std::setprecision(8) << "# dvso calibrate-vignette: V(rho^2) = 1 + sum_i c_i rho^(2 i), rho = 1 at the "
           "half diagonal from (cx, cy);\n# vignette.png holds V divided by its maximum where that exceeds 1\n"
           "coefficients: [";
    for (size_t i = 0; i < c.fit.vignette.coefficients.size(); ++i)
      out << (i ? ", " : "") << c.fit.vignette.coefficients[i];
    out << "]\ncentre: [" << c.camera.cx << ", " << c.camera.cy << "]\nimage_size: [" << c.camera.width << ", "
        << c.camera.height << "]\nlowest_relative_value: " << min_v
        << "  # vignette.png's darkest pixel (its brightest is 1)\nrms_residual: " << c.fit.rms
        << "\nrms_residual_without_vignette: " << c.fit.rms_without_vignette << "\nkeyframes: " << c.keyframes
        << "\nsegments: " << c.segments << "\npoints: " << c.fit.points << "\nobservations: " << c.fit.observations
        << "\niterations: " << c.fit.iterations << "\n";
  });
  PlotSeries data, model;
  data.label = "data: median (I - b) / (a R) per bin";
  data.thickness = 0;
  data.markers = true;
  model.label = "fitted V";
  model.color = cv::Scalar(0, 0, 200);
  for (size_t i = 0; i < c.fit.profile_rho.size(); ++i) {
    data.x.push_back(c.fit.profile_rho[i]);
    data.y.push_back(c.fit.profile_ratio[i]);
  }
  const double max_rho = c.fit.profile_rho.empty() ? 1.0 : c.fit.profile_rho.back();
  for (int i = 0; i <= 100; ++i) {
    const double r = max_rho * i / 100.0;
    model.x.push_back(r);
    model.y.push_back(c.fit.vignette.At(r * r));
  }
  PlotOptions plot;
  plot.title = "vignetting: " + std::to_string(c.fit.observations) + " samples of " + std::to_string(c.fit.points) +
               " points in " + std::to_string(c.keyframes) + " keyframes";
  plot.x_label = "rho (1 = half diagonal)";
  plot.y_label = "V";
  WritePlotPng(JoinPath(out_dir, "vignette_profile.png"), {data, model}, plot);
}

}  // namespace dvso::vo
