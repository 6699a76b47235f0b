// Linearisation of the window energy and its Hessian blocks.
//
// For every point p and residual (p, target) the residual kinds give dr/dy
// (pair parameters y = [xi_rel, a_i, b_i, a_j, b_j]) and dr/dd. The
// accumulator sums, in the Gauss-Newton sense (H = J^T W J, b = J^T W r):
//  - per (host, target) pair the 10x10 block H_yy and b_y (mapped once per pair
//    to the absolute host/target parameters with the adjoint, eq. xi_rel =
//    xi_t - Adj(T_th) xi_h, see frame_parameters.h),
//  - per point the scalar H_dd, b_d and the cross terms H_xd with every
//    keyframe it touches (absolute parameters).
// The frame-frame Hessian is dense (8N x 8N, N <= ~8), the depth block is
// diagonal, which makes the Schur complement on the inverse depths cheap:
//   H_red = H_xx - sum_p H_xd H_dd^-1 H_dx,   b_red = b_x - sum_p H_xd H_dd^-1 b_d.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "vo/optimization/frame_parameters.h"
#include "vo/optimization/residuals.h"
#include "vo/optimization/window.h"

namespace dvso::vo {

// A point addressed by its host keyframe's window index and its index there.
struct PointRef {
  int host_index = 0;
  int point_index = 0;
};

// All points of the window (or of one host keyframe when host_index >= 0).
std::vector<PointRef> CollectPoints(const std::vector<Keyframe>& keyframes, int host_index = -1);

// Per-linearisation geometry of every residual source: (host, target) pairs,
// per-host stereo geometries, and the adjoints mapping host twists.
struct WindowGeometry {
  WindowGeometry(const std::vector<Keyframe>& keyframes, const StereoCamera& camera, const WindowOptions& options);
  int IndexOf(int keyframe_id) const;
  // Geometry for `residual` of a point hosted at window index h (nullptr when
  // its target/right image/disparity is not available); *target_index is set.
  const ResidualGeometry* For(int h, const Residual& residual, int* target_index) const;

  int num_frames = 0;
  std::vector<int> ids;                      // keyframe id per window index
  std::vector<ResidualGeometry> temporal;    // h * N + t
  std::vector<Matrix6d> adjoint;             // Adj(T_th) (FEJ) per pair: xi_rel = xi_t - Adj xi_h
  std::vector<ResidualGeometry> static_stereo;   // per host (valid if has right)
  std::vector<ResidualGeometry> virtual_stereo;  // per host (valid if has D^R)
  std::vector<bool> has_static, has_virtual;
};

// Residual energies at the current state (no Jacobians). Every residual is
// evaluated; `comparable` sums the residuals that were active BEFORE this
// evaluation, each with min(energy, cap) (out of bounds counts as the cap),
// so that energies before/after an LM step compare the same residual set;
// `active` sums the residuals active now. With write_states the new
// states/energies are stored in the window.
struct WindowEnergy {
  double comparable = 0.0;
  double active = 0.0;
};
WindowEnergy EvaluateWindowEnergy(std::vector<Keyframe>* keyframes, const StereoCamera& camera,
                                  const WindowOptions& options, bool write_states);

class WindowLinearizer {
 public:
  WindowLinearizer(std::vector<Keyframe>* keyframes, const StereoCamera& camera, const WindowOptions& options);

  // Evaluates all residuals of `points` with Jacobians at the current state,
  // stores each residual's state/energy in the window, and accumulates the
  // Hessian blocks. Residuals that are out of bounds or outliers are skipped.
  void Linearize(const std::vector<PointRef>& points);

  // Reduced camera system (inverse depths eliminated) with Levenberg-Marquardt
  // damping: diag(H_xx) and H_dd are multiplied by (1 + lambda). `extra_H`,
  // `extra_b` (frame priors, may be empty) are added to H_xx, b_x before damping.
  void Reduce(double lambda, const Eigen::MatrixXd& extra_H, const Eigen::VectorXd& extra_b, Eigen::MatrixXd* H,
              Eigen::VectorXd* b) const;

  // Inverse-depth steps from the frame step dx (back-substitution):
  // dd_p = -(b_d + H_dx dx) / (H_dd (1 + lambda)). 0 for unconstrained points.
  std::vector<double> BackSubstitute(const Eigen::VectorXd& dx, double lambda) const;

  // Full undamped system [frames; depths] (8N + P) for tests of the Schur solve.
  void FullSystem(Eigen::MatrixXd* H, Eigen::VectorXd* b) const;

  // Sum of the energies of the residuals active at this linearisation.
  double energy() const { return energy_; }
  // Energy of the residuals that were active before this linearisation,
  // capped as in EvaluateWindowEnergy (for LM step acceptance).
  double comparable_energy() const { return comparable_energy_; }
  int num_active_residuals() const { return num_active_; }
  int num_frame_params() const { return kFrameParams * num_frames_; }
  const std::vector<PointRef>& points() const { return points_; }

 private:
  struct PairBlock {
    Eigen::Matrix<double, kPairParams, kPairParams> H = Eigen::Matrix<double, kPairParams, kPairParams>::Zero();
    Eigen::Matrix<double, kPairParams, 1> b = Eigen::Matrix<double, kPairParams, 1>::Zero();
  };
  struct PointBlock {
    double H_dd = 0.0;
    double H_dd_temporal = 0.0;  // part of H_dd from temporal residuals
    double b_d = 0.0;
    uint32_t frame_mask = 0;  // keyframes with non-zero cross terms
  };
  struct Partial;  // per-thread accumulators

  void LinearizeRange(size_t begin, size_t end, Partial* partial);
  void ProcessResidual(size_t i, int h, Point* point, Residual* residual, Partial* partial, ResidualEvaluation* ev);
  void AssembleFrameBlocks();

  std::vector<Keyframe>* keyframes_;
  const StereoCamera& camera_;
  const WindowOptions& options_;
  WindowGeometry geometry_;
  int num_frames_ = 0;

  std::vector<PointRef> points_;
  std::vector<PointBlock> point_blocks_;
  std::vector<double> point_cross_;  // H_xd, num_frame_params() per point
  std::vector<PairBlock> pairs_;
  Eigen::MatrixXd H_frames_;
  Eigen::VectorXd b_frames_;
  double energy_ = 0.0;
  double comparable_energy_ = 0.0;
  int num_active_ = 0;
};

}  // namespace dvso::vo
