// Solve of the (LM-damped) normal equations of the window. The inverse depths
// are eliminated by the Schur complement (WindowLinearizer::Reduce), leaving the
// dense reduced camera system over 8 parameters per keyframe (56 for N = 7),
// solved here with a dense LDLT; the depth steps follow by back-substitution.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "vo/optimization/accumulator.h"

namespace dvso::vo {

// Solves H dx = -b (H symmetric positive semi-definite). Jacobi-preconditioned
// LDLT; directions without information (zero diagonal) get dx = 0. Returns
// false when the solution is not finite.
bool SolveReducedSystem(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd* dx);

struct WindowStep {
  Eigen::VectorXd frames;     // 8 per keyframe, window order
  std::vector<double> depths; // per point of the linearizer's point list
};

// Full Schur-complement step: reduce, solve, back-substitute.
bool SolveWindowStep(const WindowLinearizer& linearizer, double lambda, const Eigen::MatrixXd& prior_H,
                     const Eigen::VectorXd& prior_b, WindowStep* step);

}  // namespace dvso::vo
