// The sliding window of the photometric bundle adjustment (DSO's "energy
// functional" state): keyframes with pose and affine brightness, the active
// points hosted in them with their inverse depths, the residuals connecting
// them, and the Gaussian marginalisation prior over the keyframe parameters.
//
// Energy (paper eq. 5.1, the total energy and eq. 5.8):
//   E = sum_p sum_{j in obs(p)} E_ij^p            (temporal, eq. 5.1)
//     + mu     sum_p E_i^{stereo,p}               (static stereo, Stereo DSO)
//     + lambda sum_p E_i^{dagger,p}                (virtual stereo, eq. 5.8)
//     + E_prior(keyframe parameters)               (marginalisation + gauge priors)
// minimised by Levenberg-Marquardt with the inverse depths eliminated by the
// Schur complement (see optimizer.cpp).
//
// Conventions:
//  - Poses are stored world-to-camera (T_cw: X_cam = T_cw * X_world); use
//    CameraToWorld() for output. Updates are left-multiplied twists [v; w]
//    (core/lie.h): T_cw <- Exp(xi) * T_cw.
//  - Pixel coordinates are level-0 pixels of the keyframe's left pyramid.
//  - Intensities come from vo::ImagePyramid (already divided by exposure
//    time when known); the affine model I_j - b_j = e^{a_j - a_i}(I_i - b_i)
//    absorbs what is left.
//  - D^R (virtual stereo) is a CV_32F right-image disparity map in level-0
//    pixels with x_left = x_right + D^R(x_right) (KITTI sign; <= 0 invalid).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.h"
#include "vo/frame/image_pyramid.h"
#include "vo/frame/stereo_brightness.h"
#include "vo/optimization/residual_pattern.h"

namespace dvso::vo {

struct PointRef;  // accumulator.h

struct WindowOptions {
  int max_keyframes = 7;                // active keyframes N (paper: 7); marginalisation keeps it
  double huber_threshold = 9.0;         // gamma of the Huber norm, intensity units (DSO setting_huberTH)
  double outlier_energy_threshold = 144.0;  // mean weighted energy per pattern pixel above which a residual is an outlier (DSO 12*12)
  double gradient_weight_c = 50.0;      // c in w_p = c^2 / (c^2 + |grad I|^2) (DSO setting_outlierTHSumComponent = 50^2)
  double image_border = 2.0;            // pattern pixels must interpolate this far inside the image (pixels)
  bool use_static_stereo = true;        // add host -> right-image residuals when a keyframe has a right pyramid
  double static_stereo_weight = 1.0;    // weight mu of the static stereo term (Stereo DSO couples with 1)
  bool use_virtual_stereo = true;       // add eq. 5.8 residuals when a keyframe has a D^R map
  double virtual_stereo_weight = 1.0;   // lambda of the total energy (paper: coupling factor)
  double virtual_stereo_baseline = 0.54;  // |t_b| = b_v in metres; vo::System sets it from dvso.virtual_baseline
  double first_pose_prior = 1e8;        // weight of the prior pinning the first keyframe's pose (gauge), per twist component
  double affine_a_prior = 1e4;          // weight pulling every keyframe's a towards 0 (brightness gauge; DSO affineOptModeA)
  double affine_b_prior = 1e2;          // weight pulling every keyframe's b towards 0 (DSO affineOptModeB)
  bool first_estimate_jacobians = true; // pose Jacobians at the keyframe's first estimate (FEJ), keeps the prior consistent
  double initial_lambda = 1e-4;         // initial Levenberg-Marquardt damping (multiplies diag(H))
  double min_idepth = 1e-5;             // inverse depths are clamped to at least this (1/m) after a step
  double convergence_step = 1e-5;       // stop when the frame update norm (and RMS relative depth update) falls below this
  double min_relative_decrease = 1e-4;  // stop when an accepted step lowers the energy by less than this fraction
  int min_residuals_to_marginalize = 1; // hosted points with fewer good temporal residuals are dropped, not marginalised
  double max_log_affine_in_window = 0.7; // keyframes whose brightness differs from the newest by more than this (|a_i - a_new|) leave (DSO setting_maxLogAffFacInWindow)
  int min_keyframes_kept = 5;           // the "lost its points" / affine rules never leave fewer keyframes than this (DSO setting_minFrames)
  int num_threads = 1;                  // threads for linearisation/accumulation (1 or 2 are sensible)

  void Check() const;
};

// Everything the frontend hands over when a frame becomes a keyframe.
struct KeyframeInput {
  int id = -1;                          // frontend frame id, unique and increasing
  Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();  // tracked pose T_cw (first estimate)
  double a = 0.0;                       // affine brightness a (eq. 5.1: I_j - b_j = e^{a_j - a_i} (I_i - b_i))
  double b = 0.0;                       // affine brightness offset b
  ImagePyramidPtr left;                 // required
  ImagePyramidPtr right;                // optional: enables static stereo residuals
  StereoBrightness right_brightness;    // I_right ~ gain (1 + radial rho^2) I_left + bias (vo/frame/stereo_brightness.h)
  cv::Mat right_disparity;              // optional CV_32F D^R: enables virtual stereo residuals
};

enum class ResidualKind : uint8_t {
  kTemporal,       // host -> another keyframe (eq. 5.1)
  kStaticStereo,   // host -> its own right image, fixed baseline (Stereo DSO)
  kVirtualStereo,  // host -> itself through the predicted D^R (eq. 5.8)
};

enum class ResidualState : uint8_t {
  kActive,       // inside the image and below the outlier threshold at the last evaluation
  kOutOfBounds,  // projects outside the target image (or behind the camera)
  kOutlier,      // energy above the outlier threshold
};

struct Residual {
  ResidualKind kind = ResidualKind::kTemporal;
  int target_id = -1;                   // target keyframe id (== host id for the stereo kinds)
  ResidualState state = ResidualState::kActive;
  float energy = 0.0f;                  // weighted Huber energy at the last evaluation
};

struct Point {
  int id = -1;                          // unique over the window's lifetime
  float u = 0.0f, v = 0.0f;             // host pixel (level 0)
  double idepth = 1.0;                  // inverse depth in the host camera (1/m)
  std::array<float, kPatternSize> host_intensity{};  // I_i at the pattern pixels around (u, v)
  float idepth_hessian = 0.0f;          // H_dd over the active residuals at the last linearisation (information on d)
  float idepth_hessian_temporal = 0.0f; // the part of idepth_hessian from temporal residuals (multi-view parallax)
  std::vector<Residual> residuals;
  // Energy of its static stereo residual when RemoveOutliers() dropped it as an outlier, -1 if it
  // did not: a point can live on through its temporal residuals after its stereo match failed, and
  // the labels must still see how badly it matched (sdso_labels max_stereo_energy[_ratio]).
  float rejected_stereo_energy = -1.0f;
};

// Energy of `point`'s static stereo residual at the last evaluation (active or outlier), else the
// one RemoveOutliers() rejected; -1 if it has none (or it left the image). What the labels filter on.
inline float StaticStereoEnergy(const Point& point) {
  for (const Residual& r : point.residuals) {
    if (r.kind == ResidualKind::kStaticStereo && r.state != ResidualState::kOutOfBounds) return r.energy;
  }
  return point.rejected_stereo_energy;
}

struct Keyframe {
  int id = -1;
  Eigen::Isometry3d world_to_camera = Eigen::Isometry3d::Identity();  // current estimate T_cw
  double a = 0.0, b = 0.0;              // current affine brightness
  // Linearisation point (first estimate, FEJ): the prior is expanded around it
  // and the pose Jacobians are evaluated at it. It follows the estimate until
  // the keyframe first receives information in the marginalisation prior
  // (fej_fixed), then stays fixed so prior and residuals agree on the
  // unobservable directions.
  Eigen::Isometry3d world_to_camera_fej = Eigen::Isometry3d::Identity();
  double a_fej = 0.0, b_fej = 0.0;
  bool fej_fixed = false;
  // Absolute priors on this keyframe's 8 parameters [xi(6), a, b] around
  // (prior_pose, 0, 0): diagonal weights, 0 = none. Carried into the
  // marginalisation prior when the keyframe leaves.
  Eigen::Matrix<double, 8, 1> prior_weight = Eigen::Matrix<double, 8, 1>::Zero();
  Eigen::Isometry3d prior_pose = Eigen::Isometry3d::Identity();
  ImagePyramidPtr left, right;
  StereoBrightness right_brightness;    // I_right ~ gain (1 + radial rho^2) I_left + bias (from KeyframeInput)
  cv::Mat right_disparity;
  std::vector<Point> points;            // active points hosted here
  int num_points_added = 0;             // points ever activated here (for the DSO marginalisation rule)
};

// A point leaving the window with its host keyframe (for point clouds, labels).
struct MarginalizedPoint {
  int host_id = -1;
  float u = 0.0f, v = 0.0f;
  double idepth = 0.0;
  Eigen::Vector3d world;                // position in world coordinates
  int num_residuals = 0;                // good temporal residuals it had
  float idepth_hessian = 0.0f;          // information on the inverse depth (H_dd, all active residuals)
  float idepth_hessian_temporal = 0.0f; // the part of it from temporal residuals only
  float mean_energy = 0.0f;             // mean energy over its active residuals
  float stereo_energy = -1.0f;          // energy of its static stereo residual (also when rejected as an outlier), -1 if none
};

struct OptimizationSummary {
  int iterations = 0;                   // linearisations performed
  int accepted_steps = 0;
  double initial_energy = 0.0;          // total energy (residuals + priors) before
  double final_energy = 0.0;            // total energy after
  int num_active_residuals = 0;         // residual (point, target) pairs used in the last linearisation
  double total_ms = 0.0;                // wall time of Optimize()
};

// The distance score for choosing which keyframe leaves the window, after DSO
// (FullSystem::flagFramesForMarginalization): with d(i, j) the distance between the
// camera centres of keyframes i and j,
//   score_i = sqrt(d(i, newest) + eps) * sum_{j != i, j != newest, j staying} 1 / (d(i, j) + eps).
// The largest score leaves first: a keyframe close to others (the sum) but far from the
// newest (the root) adds least. Differences from DSO: DSO's sum also counts the newest
// keyframe and the keyframes already flagged to leave, DSO flags at most one keyframe by
// this score per new keyframe (KeyframesToMarginalize flags as many as needed to make room)
// and never the first keyframe ever, and it has no eps under the root. Counting the newest,
// measured in session 28 (README status table, one run each, differences of at most 0.01
// points of t_rel): better for stereo on 4 of 4 sequences, worse for DVSO with exact
// disparities on 3 of 4 (equal on 1) and for mono on 3 of 4, so the newest stays out.
// `world_to_camera`: the window's keyframes, oldest first; `leaving[j]`: j is already
// chosen to leave and no longer counts.
double MarginalizationDistanceScore(const std::vector<Eigen::Isometry3d>& world_to_camera,
                                    const std::vector<bool>& leaving, int i);

class Window {
 public:
  // `camera`: level-0 intrinsics of every keyframe pyramid; its baseline is
  // used by the static stereo residuals (may be 0 in monocular mode).
  Window(const WindowOptions& options, const StereoCamera& camera);

  // Adds a keyframe (newest last) and creates temporal residuals from every
  // existing point to it. The first keyframe ever added gets the gauge prior.
  // Throws dvso::Error if the id is not new or the pyramid is missing.
  void AddKeyframe(const KeyframeInput& input);
  // Attaches/replaces D^R of a keyframe (e.g. when the network result arrives later).
  void SetRightDisparity(int keyframe_id, const cv::Mat& right_disparity);
  // The right image's brightness transfer of a keyframe (refitted after its static stereo matching).
  void SetRightBrightness(int keyframe_id, const StereoBrightness& transfer);

  // Activates a point hosted in keyframe `host_id` at pixel (u, v) with the
  // given inverse depth: temporal residuals to all other keyframes, plus the
  // static / virtual stereo residuals when available. Returns the point id,
  // or -1 when the pattern does not fit inside the host image.
  int AddPoint(int host_id, float u, float v, double idepth);

  // Runs up to `max_iterations` Levenberg-Marquardt iterations over all
  // keyframe poses / affine parameters and point inverse depths (Schur
  // complement on the depths, step accepted only if the energy decreases).
  // Stops early when converged (convergence_step, min_relative_decrease).
  OptimizationSummary Optimize(int max_iterations);

  // Drops residuals that were outliers or out of bounds at the last
  // evaluation (re-evaluates first) and removes points left without any
  // residual. Returns the number of removed points.
  int RemoveOutliers();

  // Points that the newest keyframe no longer observes leave the window (DSO
  // flagPointsForRemoval / isOOB): a point hosted in an older keyframe whose
  // residual into the newest keyframe is out of bounds (or missing), or an
  // outlier there and in the previous keyframe too, is marginalised into the
  // prior when it has at least min_residuals_to_marginalize active temporal
  // residuals, else dropped. Without this, stereo points (whose static stereo
  // residual never leaves the image) would stay forever and pin long-gone
  // keyframes in the window. Call after Optimize() and before
  // RemoveOutliers() (it needs the residual states). Returns the points that left.
  std::vector<MarginalizedPoint> MarginalizeInvisiblePoints();

  // Keyframes DSO would marginalise now, never the newest: those that kept
  // fewer than 5 % of their points or whose brightness differs too much from
  // the newest (while more than min_keyframes_kept remain), then (distance
  // heuristic of DSO) as many as needed so that at most max_keyframes - 1
  // remain, leaving room for the next keyframe. Call after Optimize() of a
  // new keyframe (DSO order).
  std::vector<int> KeyframesToMarginalize() const;
  // Marginalises keyframe `id`: its points (those with enough good residuals)
  // go into the prior through the Schur complement, then the keyframe's
  // parameters are marginalised out of the prior; residuals of other points
  // into it are dropped. Returns the points that left.
  std::vector<MarginalizedPoint> MarginalizeKeyframe(int id);

  // Accessors. Keyframes are ordered oldest first.
  int num_keyframes() const { return static_cast<int>(keyframes_.size()); }
  const Keyframe& keyframe(int index) const { return keyframes_[index]; }
  const Keyframe* FindKeyframe(int id) const;
  int num_points() const;
  Eigen::Isometry3d CameraToWorld(int keyframe_id) const;
  const WindowOptions& options() const { return options_; }
  // Replaces the options (checked); takes effect at the next call.
  void SetOptions(const WindowOptions& options);
  const StereoCamera& camera() const { return camera_; }

  // Marginalisation prior over the active keyframes (8 parameters each,
  // keyframe order, around the FEJ points); for tests and diagnostics.
  const Eigen::MatrixXd& prior_hessian() const { return prior_H_; }
  const Eigen::VectorXd& prior_gradient() const { return prior_b_; }

  // Mutable access for the optimiser internals and tests.
  std::vector<Keyframe>& mutable_keyframes() {
    residual_states_current_ = false;
    return keyframes_;
  }
  Keyframe* FindMutableKeyframe(int id);

 private:
  void AddResidualsForPoint(const Keyframe& host, Point* point) const;
  // Describes point `point_index` of keyframe `host_index` as it leaves; counts its good temporal residuals.
  MarginalizedPoint DescribeLeavingPoint(int host_index, int point_index) const;
  // Schur-complements the given points (depths eliminated, linearised at the
  // current state) into the prior and fixes the linearisation points they touch.
  void MarginalizePointsIntoPrior(const std::vector<PointRef>& points);

  WindowOptions options_;
  StereoCamera camera_;
  std::vector<Keyframe> keyframes_;
  Eigen::MatrixXd prior_H_;  // 8N x 8N
  Eigen::VectorXd prior_b_;  // 8N
  int next_point_id_ = 0;
  bool had_keyframe_ = false;
  bool residual_states_current_ = false;  // residual states evaluated at the current estimate
};

}  // namespace dvso::vo
