#include "vo/optimization/schur_solver.h"

#include <Eigen/Cholesky>

namespace dvso::vo {

bool SolveReducedSystem(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd* dx) {
  const int n = static_cast<int>(H.rows());
  // Jacobi scaling: poses (metres, radians), a and b have very different
  // magnitudes; scaling to unit diagonal keeps the factorisation well conditioned.
  Eigen::VectorXd scale(n);
  for (int i = 0; i < n; ++i) scale(i) = H(i, i) > 1e-30 ? 1.0 / std::sqrt(H(i, i)) : 0.0;
  const Eigen::MatrixXd Hs = scale.asDiagonal() * H * scale.asDiagonal();
  Eigen::MatrixXd Hreg = Hs;
  for (int i = 0; i < n; ++i) {
    if (scale(i) == 0.0) Hreg(i, i) = 1.0;  // no information: keep fixed
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Hreg);
  const Eigen::VectorXd y = ldlt.solve(-(scale.asDiagonal() * b));
  *dx = scale.asDiagonal() * y;
  return dx->allFinite();
}

bool SolveWindowStep(const WindowLinearizer& linearizer, double lambda, const Eigen::MatrixXd& prior_H,
                     const Eigen::VectorXd& prior_b, WindowStep* step) {
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  linearizer.Reduce(lambda, prior_H, prior_b, &H, &b);
  if (!SolveReducedSystem(H, b, &step->frames)) return false;
  step->depths = linearizer.BackSubstitute(step->frames, lambda);
  return true;
}

}  // namespace dvso::vo
