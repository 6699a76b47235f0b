#include "core/simulator.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "core/error.h"
#include "core/trajectory.h"

namespace dvso {
namespace {
}  // namespace

void SimulatorOptions::Check() const {
  Require(world_version >= 1 && world_version <= kSimulatorWorldVersion,
          "--world-version must be in [1, " + std::to_string(kSimulatorWorldVersion) + "]");
  Require(first_frame >= 0, "--first must be >= 0");
  Require(num_frames == -1 || num_frames >= 1, "--count must be >= 1 (or -1 for all frames)");
  Require(stride >= 1, "--stride must be >= 1");
  Require(trajectory_path.empty() ? num_frames >= 1 : true, "a generated path needs an explicit --count");
  Require(std::isfinite(generated_speed) && generated_speed > 0 && generated_speed < 60,
          "--speed must be in (0, 60) m/s");
  camera.Check();
  Require(camera.left.width >= 16 && camera.left.height >= 16, "image size must be at least 16x16");
  Require(camera.baseline > 0 && camera.baseline < 10, "baseline must be in (0, 10) m");
  Require(camera_height > 0.2 && camera_height < 10, "camera height must be in (0.2, 10) m");
  Require(frame_interval > 0, "frame interval must be > 0 s");
  Require(max_distance > 10 && max_distance <= 1000, "max distance must be in (10, 1000] m");
  Require(exposure_sigma >= 0 && exposure_sigma < 1, "exposure sigma must be in [0, 1)");
  Require(exposure_max >= 0 && exposure_max < 2, "exposure bound must be in [0, 2)");
  Require(bias_sigma >= 0 && bias_sigma < 20, "bias sigma must be in [0, 20) grey levels");
  Require(right_gain >= 0.5 && right_gain <= 2, "right gain must be in [0.5, 2]");
  Require(std::abs(right_bias) <= 40, "right bias must be in [-40, 40] grey levels");
  Require(vignetting_strength >= 0 && vignetting_strength < 1, "vignetting strength must be in [0, 1)");
  Require(right_vignetting_strength < 1, "right vignetting strength must be in [0, 1) (< 0: the left one's)");
  Require(noise_sigma >= 0 && noise_sigma < 50, "noise sigma must be in [0, 50) grey levels");
  Require(num_threads >= 1 && num_threads <= 64, "threads must be in [1, 64]");
  Require(texture_size >= 64 && texture_size <= 4096 && (texture_size & (texture_size - 1)) == 0,
          "texture size must be a power of two in [64, 4096]");
  Require(scene.building_density >= 0 && scene.building_density <= 1, "building density must be in [0, 1]");
  Require(scene.car_density >= 0 && scene.car_density <= 1, "car density must be in [0, 1]");
  Require(scene.tree_density >= 0 && scene.tree_density <= 5, "tree density must be in [0, 5]");
  Require(exposure_level > 0.05 && exposure_level < 4, "exposure level must be in (0.05, 4)");
  Require(height_jitter >= 0 && height_jitter < 0.5, "height jitter must be in [0, 0.5) m");
  Require(car_detail <= 1, "car detail must be a share in [0, 1] (or < 0: the appearance's own)");
}

StreetSimulator::StreetSimulator(const SimulatorOptions& options) : options_(options) {
  options_.Check();
  if (options_.vary_appearance) {
    options_.scene.appearance = sim::RandomAppearance(options_.seed);
    std::mt19937_64 look_rng(options_.seed * 0x9E3779B97F4A7C15ull + 0x1F2Eu);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    options_.exposure_level = 0.6 + 0.5 * unit(look_rng);
    options_.camera_height += kVariedCameraHeightRange * (2 * unit(look_rng) - 1);
    options_.height_jitter = std::max(options_.height_jitter, kVariedHeightJitter);
  }
  if (options_.car_detail >= 0) options_.scene.appearance.car_detail = static_cast<float>(options_.car_detail);
  // Trajectory: from file or generated.
  if (!options_.trajectory_path.empty()) {
    const Trajectory trajectory = ReadTrajectory(options_.trajectory_path, TrajectoryFormat::kKitti);
    RequireFile(!trajectory.empty(), options_.trajectory_path, "trajectory has no poses");
    // KITTI's GT rotations are orthonormal only to ~1e-7; project them onto
    // SO(3) so that poses relative to the first frame start exactly at identity.
    for (const auto& p : trajectory.poses) {
      Eigen::Isometry3d T = p.T_world_camera;
      T.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
      trajectory_.push_back(T);
    }
  } else {
    const int needed = options_.first_frame + (options_.num_frames - 1) * options_.stride + 1;
    trajectory_ = sim::GenerateDrivingPath(needed, options_.generated_speed, options_.frame_interval, options_.seed);
  }
  options_.scene.extensions_yield = options_.world_version >= 3;
  if (options_.world_version >= 2)
    sim::ApplyAltitudeCorrections(sim::AltitudeCorrections(trajectory_, sim::AltitudeReconciliationOptions()),
                                  &trajectory_);
  const int total = static_cast<int>(trajectory_.size());
  if (options_.first_frame >= total)
    throw Error(options_.trajectory_path, "--first " + std::to_string(options_.first_frame) +
                                              " is beyond the last pose (" + std::to_string(total - 1) + ")");
  for (int i = options_.first_frame; i < total; i += options_.stride) {
    if (options_.num_frames >= 0 && static_cast<int>(frame_poses_.size()) >= options_.num_frames) break;
    frame_poses_.push_back(i);
  }
  if (options_.num_frames >= 0 && static_cast<int>(frame_poses_.size()) < options_.num_frames)
    throw Error(options_.trajectory_path, "only " + std::to_string(frame_poses_.size()) +
                                              " frames available from --first with this --stride, " +
                                              std::to_string(options_.num_frames) + " requested");

  // World.
  path_ = std::make_unique<sim::StreetPath>(trajectory_, options_.camera_height, 2.0, 300.0);
  textures_ = std::make_unique<sim::TextureBank>(options_.seed, options_.texture_size);
  scene_ = sim::BuildStreetScene(*path_, options_.scene, options_.seed);
  renderer_ = std::make_unique<sim::Renderer>(scene_, *textures_, options_.camera.left, options_.num_threads,
                                              options_.max_distance, options_.edge_antialiasing,
                                              /*uncovered_subsamples_see_sky=*/options_.world_version < 4);

  // Exposure drift: mean-reverting random walks of log gain and bias (DSO's
  // affine brightness a, b), the same for the left and right image of a frame.
  std::mt19937_64 rng(options_.seed * 2862933555777941757ull + 3037000493ull);
  std::normal_distribution<double> gauss(0.0, 1.0);
  double a = 0, b = 0;
  for (int i = 0; i < num_frames(); ++i) {
    if (options_.exposure_drift && i > 0) {
      a = std::clamp(0.98 * a + options_.exposure_sigma * gauss(rng), -options_.exposure_max, options_.exposure_max);
      b = std::clamp(0.95 * b + options_.bias_sigma * gauss(rng), -8.0, 8.0);
    }
    log_gain_.push_back(a);
    bias_.push_back(b);
  }
  // Height bounce: a smooth mean-reverting walk in [-jitter, jitter], applied to
  // the rendered poses after the road was laid, so GT poses include it.
  height_offset_.assign(num_frames(), 0.0);
  if (options_.height_jitter > 0) {
    std::mt19937_64 bounce(options_.seed * 0xD1B54A32D192ED03ull + 77u);
    double h = 0, v = 0;
    for (int i = 0; i < num_frames(); ++i) {
      v = 0.6 * v + 0.35 * options_.height_jitter * gauss(bounce) - 0.2 * h;
      h = std::clamp(h + v, -options_.height_jitter, options_.height_jitter);
      height_offset_[i] = h;
      trajectory_[frame_poses_[i]].translation() += h * path_->down();
    }
  }
}

StreetSimulator::~StreetSimulator() = default;

sim::Photometric StreetSimulator::Exposure(int i, int view) const {
  Require(i >= 0 && i < num_frames(), "frame index out of range");
  sim::Photometric p;
  // Overall exposure 0.85 leaves head room for bright facades and sky.
  p.gain = options_.exposure_level * std::exp(log_gain_[i]);
  p.bias = bias_[i];
  if (view == 1) {
    p.gain *= options_.right_gain;
    p.bias += options_.right_bias;
  }
  const bool own_right_vignetting = view == 1 && options_.right_vignetting_strength >= 0;
  p.vignetting_strength = !options_.vignetting   ? 0.0
                          : own_right_vignetting ? options_.right_vignetting_strength
                                                 : options_.vignetting_strength;
  p.noise_sigma = options_.noise ? options_.noise_sigma : 0.0;
  p.noise_seed = (options_.seed * 0x9E3779B97F4A7C15ull) ^ (static_cast<uint64_t>(i) * 2 + view + 1) * 0xD1B54A32D192ED03ull;
  return p;
}

Eigen::Isometry3d StreetSimulator::WorldFromCamera(int i) const {
  Require(i >= 0 && i < num_frames(), "frame index out of range");
  return trajectory_[frame_poses_[i]];
}

SimulatedFrame StreetSimulator::Render(int i) const {
  Require(i >= 0 && i < num_frames(), "frame index out of range");
  SimulatedFrame frame;
  frame.index = i;
  frame.pose_index = frame_poses_[i];
  frame.timestamp = i * options_.stride * options_.frame_interval;
  frame.T_world_camera = WorldFromCamera(i);
  frame.T_first_camera = WorldFromCamera(0).inverse() * frame.T_world_camera;
  frame.photometric = Exposure(i, 0);
  Eigen::Isometry3d T_world_right = frame.T_world_camera;
  T_world_right.translate(Eigen::Vector3d(options_.camera.baseline, 0, 0));
  frame.left = renderer_->Render(frame.T_world_camera, frame.photometric, options_.color);
  frame.right = renderer_->Render(T_world_right, Exposure(i, 1), options_.color);
  const double fxb = options_.camera.FxB();
  auto to_disparity = [fxb](const cv::Mat& depth) {
    cv::Mat disparity(depth.size(), CV_32FC1);
    for (int y = 0; y < depth.rows; ++y) {
      const float* z = depth.ptr<float>(y);
      float* d = disparity.ptr<float>(y);
      for (int x = 0; x < depth.cols; ++x) d[x] = z[x] > 0 ? static_cast<float>(fxb / z[x]) : 0.f;
    }
    return disparity;
  };
  frame.disparity_left = to_disparity(frame.left.depth);
  frame.disparity_right = to_disparity(frame.right.depth);
  return frame;
}

}  // namespace dvso
