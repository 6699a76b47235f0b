#include "vo/optimization/window.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "vo/optimization/frame_parameters.h"

namespace dvso::vo {

void WindowOptions::Check() const {
  Require(max_keyframes >= 2 && max_keyframes <= 30, "window: max_keyframes must be in [2, 30]");
  Require(huber_threshold > 0, "window: huber_threshold must be > 0");
  Require(outlier_energy_threshold > 0, "window: outlier_energy_threshold must be > 0");
  Require(gradient_weight_c > 0, "window: gradient_weight_c must be > 0");
  Require(image_border >= 1.0, "window: image_border must be >= 1 (gradients at the outermost pixel are one-sided)");
  Require(static_stereo_weight >= 0 && virtual_stereo_weight >= 0, "window: stereo weights must be >= 0");
  Require(virtual_stereo_baseline > 0, "window: virtual_stereo_baseline must be > 0");
  Require(first_pose_prior >= 0 && affine_a_prior >= 0 && affine_b_prior >= 0, "window: priors must be >= 0");
  Require(initial_lambda >= 0, "window: initial_lambda must be >= 0");
  Require(min_idepth > 0, "window: min_idepth must be > 0");
  Require(convergence_step > 0, "window: convergence_step must be > 0");
  Require(min_relative_decrease >= 0, "window: min_relative_decrease must be >= 0");
  Require(min_residuals_to_marginalize >= 1, "window: min_residuals_to_marginalize must be >= 1");
  Require(max_log_affine_in_window > 0, "window: max_log_affine_in_window must be > 0");
  Require(min_keyframes_kept >= 1, "window: min_keyframes_kept must be >= 1");
  Require(num_threads >= 1 && num_threads <= 64, "window: num_threads must be in [1, 64]");
}

Window::Window(const WindowOptions& options, const StereoCamera& camera) : options_(options), camera_(camera) {
  options_.Check();
  camera_.left.Check();
  Require(camera_.baseline >= 0, "window: baseline must be >= 0");
}

void Window::SetOptions(const WindowOptions& options) {
  options.Check();
  options_ = options;
  residual_states_current_ = false;
}

const Keyframe* Window::FindKeyframe(int id) const {
  for (const Keyframe& kf : keyframes_) {
    if (kf.id == id) return &kf;
  }
  return nullptr;
}

Keyframe* Window::FindMutableKeyframe(int id) {
  residual_states_current_ = false;
  for (Keyframe& kf : keyframes_) {
    if (kf.id == id) return &kf;
  }
  return nullptr;
}

int Window::num_points() const {
  int n = 0;
  for (const Keyframe& kf : keyframes_) n += static_cast<int>(kf.points.size());
  return n;
}

Eigen::Isometry3d Window::CameraToWorld(int keyframe_id) const {
  const Keyframe* kf = FindKeyframe(keyframe_id);
  Require(kf != nullptr, "window: no keyframe with id " + std::to_string(keyframe_id));
  return kf->world_to_camera.inverse();
}

static void CheckDisparityMap(const cv::Mat& map, const PyramidLevel& level) {
  Require(map.type() == CV_32FC1, "window: D^R must be CV_32FC1");
  Require(map.cols == level.width && map.rows == level.height,
          "window: D^R size differs from the keyframe image size");
}

static void CheckBrightnessTransfer(const StereoBrightness& transfer) {
  Require(std::isfinite(transfer.gain) && transfer.gain > 0 && std::isfinite(transfer.bias) &&
              std::isfinite(transfer.radial) && transfer.radial > -1,
          "window: the right image's brightness transfer is not finite with a positive gain and radial > -1");
}

void Window::AddKeyframe(const KeyframeInput& input) {
  Require(input.left != nullptr, "window: keyframe " + std::to_string(input.id) + " has no image pyramid");
  Require(FindKeyframe(input.id) == nullptr, "window: keyframe id " + std::to_string(input.id) + " already exists");
  const PyramidLevel& level0 = input.left->level(0);
  Require(level0.width == camera_.left.width && level0.height == camera_.left.height,
          "window: keyframe image size differs from the camera");
  if (input.right) {
    Require(input.right->width(0) == level0.width && input.right->height(0) == level0.height,
            "window: right image size differs from the left");
  }
  if (!input.right_disparity.empty()) CheckDisparityMap(input.right_disparity, level0);
  Require(std::isfinite(input.a) && std::isfinite(input.b) && input.world_to_camera.matrix().allFinite(),
          "window: keyframe parameters are not finite");

  Keyframe kf;
  kf.id = input.id;
  kf.world_to_camera = input.world_to_camera;
  kf.a = input.a;
  kf.b = input.b;
  kf.world_to_camera_fej = input.world_to_camera;
  kf.a_fej = input.a;
  kf.b_fej = input.b;
  kf.left = input.left;
  kf.right = input.right;
  CheckBrightnessTransfer(input.right_brightness);
  kf.right_brightness = input.right_brightness;
  kf.right_disparity = input.right_disparity;
  kf.prior_pose = input.world_to_camera;
  kf.prior_weight(6) = options_.affine_a_prior;
  kf.prior_weight(7) = options_.affine_b_prior;
  if (!had_keyframe_) {
    // Gauge: the first keyframe's pose is pinned by a strong prior, which is
    // carried into the marginalisation prior when it leaves (as DSO does).
    kf.prior_weight.head<6>().setConstant(options_.first_pose_prior);
    had_keyframe_ = true;
  }
  // New temporal residuals from every existing point into the new keyframe.
  for (Keyframe& host : keyframes_) {
    for (Point& p : host.points) p.residuals.push_back({ResidualKind::kTemporal, kf.id});
  }
  keyframes_.push_back(std::move(kf));
  residual_states_current_ = false;

  // Grow the prior by an empty block.
  const int n = kFrameParams * num_keyframes();
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  if (prior_H_.rows() > 0) {
    H.topLeftCorner(prior_H_.rows(), prior_H_.cols()) = prior_H_;
    b.head(prior_b_.size()) = prior_b_;
  }
  prior_H_ = std::move(H);
  prior_b_ = std::move(b);
}

void Window::SetRightBrightness(int keyframe_id, const StereoBrightness& transfer) {
  Keyframe* kf = FindMutableKeyframe(keyframe_id);
  Require(kf != nullptr, "window: no keyframe with id " + std::to_string(keyframe_id));
  CheckBrightnessTransfer(transfer);
  kf->right_brightness = transfer;
}

void Window::SetRightDisparity(int keyframe_id, const cv::Mat& right_disparity) {
  Keyframe* kf = FindMutableKeyframe(keyframe_id);
  Require(kf != nullptr, "window: no keyframe with id " + std::to_string(keyframe_id));
  CheckDisparityMap(right_disparity, kf->left->level(0));
  const bool had = !kf->right_disparity.empty();
  kf->right_disparity = right_disparity;
  if (had || !options_.use_virtual_stereo) return;
  for (Point& p : kf->points) p.residuals.push_back({ResidualKind::kVirtualStereo, kf->id});
}

void Window::AddResidualsForPoint(const Keyframe& host, Point* point) const {
  for (const Keyframe& target : keyframes_) {
    if (target.id != host.id) point->residuals.push_back({ResidualKind::kTemporal, target.id});
  }
  if (host.right && options_.use_static_stereo) {
    point->residuals.push_back({ResidualKind::kStaticStereo, host.id});
  }
  if (!host.right_disparity.empty() && options_.use_virtual_stereo) {
    point->residuals.push_back({ResidualKind::kVirtualStereo, host.id});
  }
}

int Window::AddPoint(int host_id, float u, float v, double idepth) {
  Keyframe* host = FindMutableKeyframe(host_id);
  Require(host != nullptr, "window: AddPoint: no keyframe with id " + std::to_string(host_id));
  Require(std::isfinite(u) && std::isfinite(v) && std::isfinite(idepth), "window: AddPoint: non-finite input");
  const PyramidLevel& level = host->left->level(0);
  Point point;
  point.u = u;
  point.v = v;
  point.idepth = std::max(idepth, options_.min_idepth);
  for (int k = 0; k < kPatternSize; ++k) {
    const float x = u + kPatternOffsets[k][0];
    const float y = v + kPatternOffsets[k][1];
    if (!level.InBounds(x, y, 1.0f)) return -1;
    point.host_intensity[k] = level.InterpolateIntensity(x, y);
  }
  point.id = next_point_id_++;
  AddResidualsForPoint(*host, &point);
  host->points.push_back(std::move(point));
  ++host->num_points_added;
  return host->points.back().id;
}

}  // namespace dvso::vo
