// Coarse-to-fine direct image alignment of a new frame against the newest
// keyframe (DSO's CoarseTracker): estimates the relative SE(3) pose and the
// affine brightness transfer (I_new ~ e^a I_ref + b) by minimising the Huber
// norm of photometric residuals of the keyframe's depth-map points, level by
// level with Levenberg-Marquardt. Several motion hypotheses are tried when the
// first one does not track well (TrackWithHypotheses).
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "vo/frame/image_pyramid.h"
#include "vo/optimization/residual_pattern.h"

namespace dvso::vo {

struct CoarseTrackerOptions {
  double huber_threshold = 9.0;         // Huber threshold on intensity residuals (DSO setting_huberTH)
  double cutoff_threshold = 20.0;       // residuals above this count as outliers (DSO setting_coarseCutoffTH)
  double gradient_weight_c = 50.0;      // w = c^2 / (c^2 + |grad I|^2) (DSO setting_outlierTHSumComponent)
  int max_iterations_finest = 10;       // LM iterations at level 0 (DSO: 10, 20, 50, 50, 50)
  int max_iterations_coarse = 50;       // LM iterations at the coarser levels
  double initial_lambda = 0.01;         // LM damping start
  double convergence_eps = 1e-3;        // stop when the update norm falls below this
  double max_affine_a = 1.0;            // |log brightness ratio| above this = failure
  double min_inlier_fraction = 0.3;     // fewer inliers at level 0 = failure
  int min_points = 50;                  // fewer usable points at level 0 = failure
  double retrack_ratio = 1.5;           // a hypothesis is good when rmse < ratio * reference rmse (DSO setting_reTrackThreshold)
  bool estimate_affine = true;          // estimate (a, b); off = fixed to the initial guess
  void Check() const;
};

// Squared optical flow (pixels^2) of one reference point, the inputs of DSO's
// keyframe criteria: under the full motion (rotation + translation) and under
// the translation alone. `ray` = ((u - cx) / fx, (v - cy) / fy, 1) of the point
// at (u, v) with inverse depth `idepth`; T maps reference-camera points into
// the new camera. A point that the translation alone would move behind the
// camera (z <= kMinProjectedDepth) has no translation-only flow: DSO divides
// by that z unchecked and adds a huge or sign-flipped value.
struct PointFlow {
  bool has_full = false;         // the full motion keeps the point in front of the camera
  bool has_translation = false;  // the translation alone keeps it in front
  float sq_full = 0;
  float sq_translation = 0;
};
inline constexpr float kMinProjectedDepth = 1e-6f;  // projected z (scaled by idepth) below this = behind the camera
// `q_full` = R * ray + t * idepth, the point under the full motion scaled by idepth (the tracker has it
// already).
PointFlow ComputePointFlow(const Eigen::Vector3f& q_full, const Eigen::Vector3f& t, const Eigen::Vector3f& ray,
                           float idepth, float fx, float fy);

// One reference point at level 0 of the reference keyframe.
struct ReferencePoint {
  float u = 0;       // pixel x, level 0
  float v = 0;       // pixel y, level 0
  float idepth = 0;  // inverse depth in the reference camera (> 0)
};

struct TrackingResult {
  bool success = false;
  Eigen::Isometry3d T_new_ref = Eigen::Isometry3d::Identity();  // maps reference-camera points into the new camera
  double affine_a = 0;  // I_new ~ exp(a) * I_ref + b
  double affine_b = 0;
  double rmse = 0;              // final level-0 RMSE of the Huber-weighted residuals
  double inlier_fraction = 0;   // residuals below the cutoff at level 0
  int num_residuals = 0;        // usable residuals at level 0
  // DSO keyframe criteria inputs (mean squared optical flow at level 0):
  double flow_sq_t = 0;   // flow induced by the translation only
  double flow_sq_rt = 0;  // flow induced by rotation + translation
  int hypotheses_tried = 0;
};

// Projects the linear part back onto SO(3). Chained products and transposed
// inverses of Isometry3d accumulate rounding that the constant-velocity
// prediction would otherwise amplify frame after frame.
inline Eigen::Isometry3d Orthonormalized(const Eigen::Isometry3d& T) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  out.translation() = T.translation();
  return out;
}

// Points closer than this to the border of a level are not used.
constexpr int kTrackerBorder = 2;

class CoarseTracker {
 public:
  explicit CoarseTracker(const CoarseTrackerOptions& options = {});

  // Sets the reference keyframe: its pyramid and the points (u, v, idepth at
  // level 0) with known depth. Builds a per-level inverse-depth map by
  // averaging the points falling into each cell (DSO makeCoarseDepth).
  void SetReference(ImagePyramidPtr reference, const std::vector<ReferencePoint>& points);
  bool has_reference() const { return reference_ != nullptr; }
  const ImagePyramid* reference() const { return reference_.get(); }
  int num_reference_points(int level = 0) const;

  // Aligns `frame` starting from the guess (T_new_ref, a, b). `max_level`
  // (< 0 = all) limits the coarsest level used.
  TrackingResult Track(const ImagePyramid& frame, const Eigen::Isometry3d& T_new_ref_guess, double a_guess = 0,
                       double b_guess = 0, int max_level = -1) const;

  // Tries `guesses` in order and returns the best; stops early when a result's
  // rmse is below retrack_ratio * reference_rmse (reference_rmse <= 0, e.g. the
  // first frame of a new map: tries them all).
  TrackingResult TrackWithHypotheses(const ImagePyramid& frame, const std::vector<Eigen::Isometry3d>& guesses,
                                     double a_guess, double b_guess, double reference_rmse) const;

  // Standard hypothesis set (DSO trackNewCoarse): constant velocity, double,
  // half, zero motion w.r.t. the last frame, then small rotation perturbations.
  static std::vector<Eigen::Isometry3d> MotionHypotheses(const Eigen::Isometry3d& T_last_ref,
                                                          const Eigen::Isometry3d& T_last_to_prev_velocity);

 private:
  struct LevelPoint {
    float u, v, idepth, intensity;
  };
  struct LevelStats {
    double energy = 0;
    int num = 0;
    int num_inliers = 0;
    int num_flow_t = 0;  // points with a translation-only flow (ComputePointFlow)
    double flow_sq_t = 0;
    double flow_sq_rt = 0;
  };
  using Vector8d = Eigen::Matrix<double, 8, 1>;
  using Matrix8d = Eigen::Matrix<double, 8, 8>;

  // Accumulates the Gauss-Newton system (if H, g non-null) and the energy at one level.
  LevelStats Evaluate(const PyramidLevel& target, int level, const Eigen::Isometry3d& T, double a, double b,
                      double cutoff_threshold, Matrix8d* H, Vector8d* g) const;

  CoarseTrackerOptions options_;
  ImagePyramidPtr reference_;
  std::vector<std::vector<LevelPoint>> level_points_;
};

}  // namespace dvso::vo
