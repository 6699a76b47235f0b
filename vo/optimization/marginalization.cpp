#include "vo/optimization/marginalization.h"

#include <Eigen/Eigenvalues>
#include <vector>

namespace dvso::vo {

Eigen::VectorXd FirstEstimateDifference(const std::vector<Keyframe>& keyframes) {
  Eigen::VectorXd dx(kFrameParams * keyframes.size());
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const Keyframe& kf = keyframes[i];
    dx.segment<6>(kFrameParams * i) = PoseDifference(kf.world_to_camera, kf.world_to_camera_fej);
    dx(kFrameParams * i + 6) = kf.a - kf.a_fej;
    dx(kFrameParams * i + 7) = kf.b - kf.b_fej;
  }
  return dx;
}

void SyncFreeLinearizationPoints(std::vector<Keyframe>* keyframes) {
  for (Keyframe& kf : *keyframes) {
    if (kf.fej_fixed) continue;
    kf.world_to_camera_fej = kf.world_to_camera;
    kf.a_fej = kf.a;
    kf.b_fej = kf.b;
  }
}

void FixConnectedLinearizationPoints(const Eigen::MatrixXd& prior_H, std::vector<Keyframe>* keyframes) {
  for (size_t i = 0; i < keyframes->size(); ++i) {
    if (prior_H.rows() == static_cast<Eigen::Index>(kFrameParams * keyframes->size()) &&
        prior_H.middleRows<kFrameParams>(kFrameParams * i).cwiseAbs().maxCoeff() > 0.0) {
      (*keyframes)[i].fej_fixed = true;
    }
  }
}

void AbsoluteFramePrior(const Keyframe& kf, Matrix8d* H, Vector8d* b, double* energy) {
  Vector8d e;
  e.head<6>() = PoseDifference(kf.world_to_camera, kf.prior_pose);
  e(6) = kf.a;
  e(7) = kf.b;
  *H = kf.prior_weight.asDiagonal();
  *b = kf.prior_weight.cwiseProduct(e);
  *energy = e.dot(kf.prior_weight.cwiseProduct(e));
}

FramePriorTerms EvaluateFramePriors(const std::vector<Keyframe>& keyframes, const Eigen::MatrixXd& prior_H,
                                    const Eigen::VectorXd& prior_b) {
  const int n = kFrameParams * static_cast<int>(keyframes.size());
  FramePriorTerms terms;
  terms.H.setZero(n, n);
  terms.b.setZero(n);
  if (prior_H.rows() == n && n > 0) {
    const Eigen::VectorXd dx = FirstEstimateDifference(keyframes);
    terms.H = prior_H;
    terms.b = prior_b + prior_H * dx;
    terms.energy = 2.0 * prior_b.dot(dx) + dx.dot(prior_H * dx);
  }
  for (size_t i = 0; i < keyframes.size(); ++i) {
    Matrix8d H;
    Vector8d b;
    double energy = 0.0;
    AbsoluteFramePrior(keyframes[i], &H, &b, &energy);
    terms.H.block<8, 8>(kFrameParams * i, kFrameParams * i) += H;
    terms.b.segment<8>(kFrameParams * i) += b;
    terms.energy += energy;
  }
  return terms;
}

void AddToPrior(const Eigen::MatrixXd& H_m, const Eigen::VectorXd& b_m, const Eigen::VectorXd& dx,
                Eigen::MatrixXd* prior_H, Eigen::VectorXd* prior_b) {
  *prior_H += H_m;
  *prior_b += b_m - H_m * dx;
}

void MarginalizeBlock(int offset, int size, Eigen::MatrixXd* H, Eigen::VectorXd* b) {
  const int n = static_cast<int>(H->rows());
  const int rest = n - size;
  // Permute [kept; marginalised].
  Eigen::VectorXi order(n);
  int k = 0;
  for (int i = 0; i < n; ++i) {
    if (i < offset || i >= offset + size) order(k++) = i;
  }
  for (int i = 0; i < size; ++i) order(k++) = offset + i;
  Eigen::MatrixXd P(n, n);
  Eigen::VectorXd q(n);
  for (int i = 0; i < n; ++i) {
    q(i) = (*b)(order(i));
    for (int j = 0; j < n; ++j) P(i, j) = (*H)(order(i), order(j));
  }
  const Eigen::MatrixXd H_mm = 0.5 * (P.bottomRightCorner(size, size) + P.bottomRightCorner(size, size).transpose());
  // Pseudo-inverse through the eigen-decomposition (robust to a block that
  // received no information, e.g. a keyframe without points).
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H_mm);
  const double max_ev = std::max(eig.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
  Eigen::VectorXd inv_ev = eig.eigenvalues();
  for (int i = 0; i < size; ++i) inv_ev(i) = inv_ev(i) > kPriorNullEigenvalueFraction * max_ev ? 1.0 / inv_ev(i) : 0.0;
  const Eigen::MatrixXd H_mm_inv = eig.eigenvectors() * inv_ev.asDiagonal() * eig.eigenvectors().transpose();
  const Eigen::MatrixXd H_rm = P.topRightCorner(rest, size);
  Eigen::MatrixXd H_new = P.topLeftCorner(rest, rest) - H_rm * H_mm_inv * H_rm.transpose();
  const Eigen::VectorXd b_new = q.head(rest) - H_rm * (H_mm_inv * q.tail(size));
  *H = 0.5 * (H_new + H_new.transpose());
  *b = b_new;
}

int ProjectPriorToPositiveSemidefinite(Eigen::MatrixXd* H, Eigen::VectorXd* b) {
  // Only the parameters the prior touches: rows that are exactly zero (a keyframe
  // without prior information) stay exactly zero, so FixConnectedLinearizationPoints
  // still tells them apart.
  std::vector<int> touched;
  for (int i = 0; i < H->rows(); ++i) {
    if (H->row(i).cwiseAbs().maxCoeff() > 0.0) touched.push_back(i);
  }
  const int n = static_cast<int>(touched.size());
  if (n == 0) return 0;
  Eigen::MatrixXd sub(n, n);
  Eigen::VectorXd sub_b(n);
  for (int i = 0; i < n; ++i) {
    sub_b(i) = (*b)(touched[i]);
    for (int j = 0; j < n; ++j) sub(i, j) = 0.5 * ((*H)(touched[i], touched[j]) + (*H)(touched[j], touched[i]));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(sub);
  const Eigen::VectorXd& values = eig.eigenvalues();  // ascending
  const double cut = kPriorNullEigenvalueFraction * std::max(values(n - 1), 0.0);
  int removed = 0;
  while (removed < n && values(removed) <= cut) ++removed;
  if (removed == 0) return 0;
  const Eigen::MatrixXd null_space = eig.eigenvectors().leftCols(removed);
  const Eigen::MatrixXd kept = eig.eigenvectors().rightCols(n - removed);
  sub = kept * values.tail(n - removed).asDiagonal() * kept.transpose();
  sub_b -= null_space * (null_space.transpose() * sub_b);
  for (int i = 0; i < n; ++i) {
    (*b)(touched[i]) = sub_b(i);
    for (int j = 0; j < n; ++j) (*H)(touched[i], touched[j]) = sub(i, j);
  }
  return removed;
}

}  // namespace dvso::vo
