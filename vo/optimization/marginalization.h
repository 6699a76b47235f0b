// The Gaussian prior over the keyframe parameters and marginalisation through
// the Schur complement (DSO's "HM, bM").
//
// The prior is stored around the keyframes' first estimates x0 (FEJ):
//   E_prior(x) = 2 b^T dx + dx^T H dx,   dx = x [-] x0 = [Log(T T0^-1), a - a0, b - b0]
// (same convention as the window's normal equations: the gradient is 2 (b + H dx)).
// New information linearised at the current x (H_m, b_m, gradient 2 b_m at x)
// enters as H += H_m, b += b_m - H_m dx (re-expanding around x0); with the
// pose Jacobians evaluated at x0 too (FEJ) the prior and the remaining
// residuals agree on the unobservable directions, so no spurious information
// (e.g. on the global gauge or, in mono, on the scale) is created.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "vo/optimization/frame_parameters.h"
#include "vo/optimization/window.h"

namespace dvso::vo {

// Moves the linearisation point of every keyframe not yet connected to the
// prior (fej_fixed false) to its current estimate.
void SyncFreeLinearizationPoints(std::vector<Keyframe>* keyframes);

// Marks keyframes whose prior block is non-zero as having a fixed linearisation point.
void FixConnectedLinearizationPoints(const Eigen::MatrixXd& prior_H, std::vector<Keyframe>* keyframes);

// dx = x [-] x0 of every keyframe, stacked in window order (8 per keyframe).
Eigen::VectorXd FirstEstimateDifference(const std::vector<Keyframe>& keyframes);

// H, b and energy of all frame priors at the current state: the
// marginalisation prior plus every keyframe's own absolute priors
// (E = sum_i w_i e_i^2, e = [Log(T T_prior^-1), a, b]).
struct FramePriorTerms {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  double energy = 0.0;
};
FramePriorTerms EvaluateFramePriors(const std::vector<Keyframe>& keyframes, const Eigen::MatrixXd& prior_H,
                                    const Eigen::VectorXd& prior_b);

// The absolute priors of one keyframe at its current state (H diagonal, b).
void AbsoluteFramePrior(const Keyframe& keyframe, Matrix8d* H, Vector8d* b, double* energy);

// Adds information (H_m, b_m) linearised at the current state to the prior
// kept around the first estimates: H += H_m, b += b_m - H_m dx.
void AddToPrior(const Eigen::MatrixXd& H_m, const Eigen::VectorXd& b_m, const Eigen::VectorXd& dx,
                Eigen::MatrixXd* prior_H, Eigen::VectorXd* prior_b);

// Marginalises the parameter block [offset, offset + size) out of (H, b) by
// the Schur complement H' = H_rr - H_rm H_mm^+ H_mr, b' = b_r - H_rm H_mm^+ b_m
// (pseudo-inverse: a block without information is simply dropped) and
// removes it from the matrices.
void MarginalizeBlock(int offset, int size, Eigen::MatrixXd* H, Eigen::VectorXd* b);

// Eigenvalues of a prior Hessian (or of the block MarginalizeBlock inverts) at
// or below this fraction of the largest one are taken for zero (roundoff of the
// Schur complements).
inline constexpr double kPriorNullEigenvalueFraction = 1e-12;

// Keeps the Gaussian prior E(dx) = 2 b.dx + dx' H dx bounded below: H becomes
// the nearest positive semi-definite matrix (eigenvalues <= the cut above, the
// negative ones included, set to 0) and b loses its components along those
// null directions. In exact arithmetic a prior made of Schur complements of
// least-squares Hessians already is so, but the subtractions in MarginalizeBlock
// (the 1e8 gauge prior of the first keyframe minus nearly the same amount)
// leave small negative eigenvalues; with a gradient along them the energy has
// no minimum and the optimiser walks the window off by hundreds of metres
// (4541-frame mono soak, frames 2848-2855; DSO orthogonalises its prior for the
// same reason). Returns the number of directions removed.
int ProjectPriorToPositiveSemidefinite(Eigen::MatrixXd* H, Eigen::VectorXd* b);

}  // namespace dvso::vo
