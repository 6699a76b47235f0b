// The Schur-complement solve of the window equals a dense solve of the full
// (frames + inverse depths) system; the accumulator's Hessian equals J^T W J
// assembled from the (finite-difference validated) per-residual Jacobians.
#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "tests/vo/test_backend_util.h"
#include "vo/optimization/accumulator.h"
#include "vo/optimization/marginalization.h"
#include "vo/optimization/schur_solver.h"

namespace dvso::vo {
namespace {

using testing::BuildSceneWindow;
using testing::SceneWindowSpec;

SceneWindowSpec SmallProblem() {
  SceneWindowSpec spec;
  spec.num_keyframes = 3;
  spec.num_hosts = 2;
  spec.grid_step = 24;
  spec.pose_noise_t = 0.02;
  spec.pose_noise_r = 0.004;
  spec.idepth_noise = 0.05;
  spec.seed = 7;
  spec.stereo = true;  // static stereo fixes the scale: the undamped system is regular
  return spec;
}

TEST(BackendSchur, ReducedSolveEqualsDenseSolve) {
  WindowOptions options;
  options.first_estimate_jacobians = false;
  auto sw = BuildSceneWindow(options, SmallProblem());
  std::vector<Keyframe>& kfs = sw.window->mutable_keyframes();
  WindowLinearizer linearizer(&kfs, sw.camera, options);
  linearizer.Linearize(CollectPoints(kfs));
  ASSERT_GT(linearizer.num_active_residuals(), 20);
  const FramePriorTerms priors = EvaluateFramePriors(kfs, sw.window->prior_hessian(), sw.window->prior_gradient());

  for (double lambda : {0.0, 1e-3, 0.5}) {
    WindowStep step;
    ASSERT_TRUE(SolveWindowStep(linearizer, lambda, priors.H, priors.b, &step));

    Eigen::MatrixXd H;
    Eigen::VectorXd b;
    linearizer.FullSystem(&H, &b);
    const int nf = linearizer.num_frame_params();
    H.topLeftCorner(nf, nf) += priors.H;
    b.head(nf) += priors.b;
    // Points without any active residual have no depth information: keep
    // them fixed in the dense system too.
    for (int i = nf; i < H.rows(); ++i) {
      if (H(i, i) < 1e-12) H(i, i) = 1.0;
    }
    H.diagonal() *= (1.0 + lambda);
    const Eigen::VectorXd dense = H.fullPivLu().solve(-b);

    const Eigen::VectorXd frames_dense = dense.head(nf);
    EXPECT_LT((step.frames - frames_dense).norm(), 1e-6 * frames_dense.norm() + 1e-12) << "lambda " << lambda;
    Eigen::VectorXd depth_schur(step.depths.size());
    for (size_t i = 0; i < step.depths.size(); ++i) depth_schur(i) = step.depths[i];
    const Eigen::VectorXd depth_dense = dense.tail(step.depths.size());
    EXPECT_LT((depth_schur - depth_dense).norm(), 1e-6 * depth_dense.norm() + 1e-12) << "lambda " << lambda;
    EXPECT_GT(frames_dense.norm(), 1e-6);  // a real step, not a trivial zero
  }
}

TEST(BackendSchur, AccumulatedHessianEqualsAssembledJacobians) {
  WindowOptions options;
  auto sw = BuildSceneWindow(options, SmallProblem());
  std::vector<Keyframe>& kfs = sw.window->mutable_keyframes();
  WindowLinearizer linearizer(&kfs, sw.camera, options);
  const std::vector<PointRef> refs = CollectPoints(kfs);
  linearizer.Linearize(refs);
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  linearizer.FullSystem(&H, &b);

  // Independent assembly: absolute Jacobians from the pair Jacobians through
  // the adjoint, written out per residual.
  const int nf = linearizer.num_frame_params();
  const int n = nf + static_cast<int>(refs.size());
  Eigen::MatrixXd H_exp = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b_exp = Eigen::VectorXd::Zero(n);
  const WindowGeometry geometry(kfs, sw.camera, options);
  for (size_t i = 0; i < refs.size(); ++i) {
    const int h = refs[i].host_index;
    const Point& p = kfs[h].points[refs[i].point_index];
    for (const Residual& r : p.residuals) {
      if (r.state != ResidualState::kActive) continue;
      int t = 0;
      const ResidualGeometry* g = geometry.For(h, r, &t);
      ASSERT_NE(g, nullptr);
      ResidualEvaluation ev;
      EvaluateResidual(*g, p, p.idepth, options, true, &ev);
      ASSERT_EQ(ev.state, ResidualState::kActive);
      for (int k = 0; k < kPatternSize; ++k) {
        Eigen::RowVectorXd J = Eigen::RowVectorXd::Zero(n);
        if (g->has_frame_jacobians) {
          const Eigen::Isometry3d T_th = kfs[t].world_to_camera_fej * kfs[h].world_to_camera_fej.inverse();
          const Eigen::Matrix<double, 1, kPairParams> Jp = ev.J_pair.row(k).cast<double>();
          J.segment<6>(8 * h) = -Jp.head<6>() * Adjoint(T_th);
          J.segment<2>(8 * h + 6) = Jp.segment<2>(6);
          J.segment<6>(8 * t) = Jp.head<6>();
          J.segment<2>(8 * t + 6) = Jp.segment<2>(8);
        }
        J(nf + static_cast<int>(i)) = ev.J_idepth(k);
        H_exp += ev.weight(k) * J.transpose() * J;
        b_exp += ev.weight(k) * ev.r(k) * J.transpose();
      }
    }
  }
  EXPECT_LT((H - H_exp).norm(), 1e-4 * H_exp.norm());
  EXPECT_LT((b - b_exp).norm(), 1e-4 * b_exp.norm());
  EXPECT_GT(H_exp.norm(), 1.0);
}

TEST(BackendSchur, TwoThreadsGiveTheSameSystem) {
  WindowOptions options;
  auto sw = BuildSceneWindow(options, SmallProblem());
  std::vector<Keyframe>& kfs = sw.window->mutable_keyframes();
  Eigen::MatrixXd H1, H2;
  Eigen::VectorXd b1, b2;
  {
    WindowLinearizer l(&kfs, sw.camera, options);
    l.Linearize(CollectPoints(kfs));
    l.FullSystem(&H1, &b1);
  }
  WindowOptions two = options;
  two.num_threads = 2;
  {
    WindowLinearizer l(&kfs, sw.camera, two);
    std::vector<PointRef> refs = CollectPoints(kfs);
    // Enough points for the linearizer to use both threads.
    while (refs.size() < 600) refs.insert(refs.end(), refs.begin(), refs.begin() + std::min<size_t>(refs.size(), 600 - refs.size()));
    l.Linearize(refs);
    Eigen::MatrixXd H;
    Eigen::VectorXd b;
    l.FullSystem(&H, &b);
    WindowLinearizer single(&kfs, sw.camera, options);
    single.Linearize(refs);
    single.FullSystem(&H2, &b2);
    EXPECT_LT((H - H2).norm(), 1e-9 * H2.norm());
    EXPECT_LT((b - b2).norm(), 1e-9 * b2.norm() + 1e-12);
  }
}

TEST(BackendSchur, MarginalizeBlockEqualsDenseMarginal) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  const int n = 20;
  Eigen::MatrixXd A(n + 5, n);
  for (int i = 0; i < A.rows(); ++i)
    for (int j = 0; j < n; ++j) A(i, j) = normal(rng);
  const Eigen::MatrixXd H = A.transpose() * A;
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) b(i) = normal(rng);
  Eigen::MatrixXd Hm = H;
  Eigen::VectorXd bm = b;
  MarginalizeBlock(8, 8, &Hm, &bm);
  ASSERT_EQ(Hm.rows(), n - 8);
  // Dense marginal: the kept block of the covariance inverted.
  std::vector<int> kept;
  for (int i = 0; i < n; ++i)
    if (i < 8 || i >= 16) kept.push_back(i);
  const Eigen::MatrixXd cov = H.inverse();
  Eigen::MatrixXd cov_kept(kept.size(), kept.size());
  Eigen::VectorXd x_full = H.ldlt().solve(-b), x_kept(kept.size());
  for (size_t i = 0; i < kept.size(); ++i) {
    x_kept(i) = x_full(kept[i]);
    for (size_t j = 0; j < kept.size(); ++j) cov_kept(i, j) = cov(kept[i], kept[j]);
  }
  EXPECT_LT((Hm - cov_kept.inverse()).norm(), 1e-8 * Hm.norm());
  // The marginal's minimiser is the full minimiser restricted to the kept block.
  EXPECT_LT((Hm.ldlt().solve(-bm) - x_kept).norm(), 1e-8 * x_kept.norm());
}

// The prior after roundoff: a PSD matrix plus a tiny negative eigenvalue with a
// gradient along it has no minimum (2 b.dx + dx'H dx -> -inf); the projection
// removes exactly that direction, keeps the rest of (H, b), and leaves rows of
// parameters without prior information exactly zero.
TEST(BackendSchur, PriorProjectionRemovesNegativeAndNullDirectionsOnly) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  const int n = 12, touched = 10;  // the last 2 parameters carry no prior information
  Eigen::MatrixXd Q = Eigen::MatrixXd::Zero(touched, touched);
  for (int i = 0; i < touched; ++i)
    for (int j = 0; j < touched; ++j) Q(i, j) = normal(rng);
  Q = Eigen::HouseholderQR<Eigen::MatrixXd>(Q).householderQ();  // orthonormal columns
  Eigen::VectorXd values(touched);
  values << -1e-3, 0.0, 1e-2, 1.0, 3.0, 10.0, 1e2, 1e4, 1e6, 1e8;  // wide like the gauge-carrying prior
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  H.topLeftCorner(touched, touched) = Q * values.asDiagonal() * Q.transpose();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  b.head(touched) = Q * Eigen::VectorXd::LinSpaced(touched, 1.0, 10.0);

  // Unbounded before: along the negative direction the energy falls without limit.
  const auto energy = [](const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const Eigen::VectorXd& dx) {
    return 2.0 * b.dot(dx) + dx.dot(H * dx);
  };
  Eigen::VectorXd down = Eigen::VectorXd::Zero(n);
  down.head(touched) = -Q.col(0);
  EXPECT_LT(energy(H, b, 1e4 * down), -1e4);

  Eigen::MatrixXd Hp = H;
  Eigen::VectorXd bp = b;
  EXPECT_EQ(ProjectPriorToPositiveSemidefinite(&Hp, &bp), 2);  // the negative and the zero eigenvalue
  EXPECT_GE(Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(Hp).eigenvalues().minCoeff(), -1e-6);
  // Eigenvectors of small eigenvalues of a matrix of norm 1e8 are accurate to ~eps * 1e8 / gap = 1e-6.
  for (int k : {0, 1}) EXPECT_NEAR(bp.head(touched).dot(Q.col(k)), 0.0, 1e-5);
  for (int k = 2; k < touched; ++k) {  // everything else is kept
    EXPECT_NEAR(bp.head(touched).dot(Q.col(k)), b.head(touched).dot(Q.col(k)), 1e-5);
    EXPECT_NEAR(Q.col(k).dot(Hp.topLeftCorner(touched, touched) * Q.col(k)), values(k), 1e-6 * values(k) + 1e-9);
  }
  EXPECT_EQ(Hp.bottomRows(2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(Hp.rightCols(2).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(bp.tail(2).cwiseAbs().maxCoeff(), 0.0);
  // Bounded now: the minimum over the kept directions, -b'H^+b, is finite.
  const Eigen::VectorXd minimiser = -Hp.completeOrthogonalDecomposition().pseudoInverse() * bp;
  EXPECT_GT(energy(Hp, bp, minimiser), -1e4);
  EXPECT_GE(energy(Hp, bp, 1e4 * down), energy(Hp, bp, minimiser) - 1e-6);

  // A prior that already is PSD comes back unchanged.
  Eigen::MatrixXd Hpsd = Hp;
  Eigen::VectorXd bpsd = bp;
  Hpsd.topLeftCorner(touched, touched) += 1e-1 * Eigen::MatrixXd::Identity(touched, touched);
  const Eigen::MatrixXd H_before = Hpsd;
  EXPECT_EQ(ProjectPriorToPositiveSemidefinite(&Hpsd, &bpsd), 0);
  EXPECT_EQ((Hpsd - H_before).norm(), 0.0);
}

}  // namespace
}  // namespace dvso::vo
