// The marginalisation prior equals the dense marginal (Schur complement of the
// full frames + inverse-depths Hessian) of a small window, and it keeps the
// unobservable (gauge) directions of a monocular window unobservable.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "tests/vo/test_backend_util.h"
#include "vo/optimization/accumulator.h"
#include "vo/optimization/marginalization.h"

namespace dvso::vo {
namespace {

using testing::BuildSceneWindow;
using testing::SceneWindowSpec;

// Dense Schur complement of H, b onto the indices in `keep`.
void DenseMarginal(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const std::vector<int>& keep,
                   Eigen::MatrixXd* H_out, Eigen::VectorXd* b_out) {
  std::vector<int> drop;
  for (int i = 0; i < H.rows(); ++i)
    if (std::find(keep.begin(), keep.end(), i) == keep.end()) drop.push_back(i);
  auto sub = [&](const std::vector<int>& r, const std::vector<int>& c) {
    Eigen::MatrixXd M(r.size(), c.size());
    for (size_t i = 0; i < r.size(); ++i)
      for (size_t j = 0; j < c.size(); ++j) M(i, j) = H(r[i], c[j]);
    return M;
  };
  Eigen::VectorXd b_keep(keep.size()), b_drop(drop.size());
  for (size_t i = 0; i < keep.size(); ++i) b_keep(i) = b(keep[i]);
  for (size_t i = 0; i < drop.size(); ++i) b_drop(i) = b(drop[i]);
  const Eigen::MatrixXd H_dd = sub(drop, drop);
  const Eigen::MatrixXd H_kd = sub(keep, drop);
  const Eigen::MatrixXd X = H_dd.ldlt().solve(H_kd.transpose());
  *H_out = sub(keep, keep) - H_kd * X;
  *b_out = b_keep - X.transpose() * b_drop;
}

SceneWindowSpec OneHostSpec() {
  SceneWindowSpec spec;
  spec.num_keyframes = 3;
  spec.num_hosts = 1;  // only the keyframe to be marginalised hosts points
  spec.grid_step = 20;
  spec.idepth_noise = 0.03;  // non-zero residuals, so b is non-trivial
  spec.seed = 5;
  return spec;
}

TEST(BackendMarginalization, PriorEqualsDenseMarginal) {
  WindowOptions options;
  options.first_pose_prior = 1e4;  // keeps the dense reference well conditioned
  auto sw = BuildSceneWindow(options, OneHostSpec());
  std::vector<Keyframe>& kfs = sw.window->mutable_keyframes();

  // Reference: full system of keyframe 0's points at the current state, plus
  // keyframe 0's own priors, marginalised densely onto keyframes 1 and 2.
  WindowLinearizer linearizer(&kfs, sw.camera, options);
  linearizer.Linearize(CollectPoints(kfs, 0));
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  linearizer.FullSystem(&H, &b);
  Matrix8d H_abs;
  Vector8d b_abs;
  double unused = 0.0;
  AbsoluteFramePrior(kfs[0], &H_abs, &b_abs, &unused);
  H.topLeftCorner<8, 8>() += H_abs;
  b.head<8>() += b_abs;
  std::vector<int> keep;
  for (int i = 8; i < 24; ++i) keep.push_back(i);
  // Points without information (no active residual) are removed from both.
  Eigen::MatrixXd H_clean = H;
  for (int i = 24; i < H.rows(); ++i)
    if (H(i, i) < 1e-12) H_clean(i, i) = 1.0;
  Eigen::MatrixXd H_exp;
  Eigen::VectorXd b_exp;
  DenseMarginal(H_clean, b, keep, &H_exp, &b_exp);

  const int points_before = sw.window->num_points();
  const std::vector<MarginalizedPoint> leaving = sw.window->MarginalizeKeyframe(0);
  EXPECT_EQ(static_cast<int>(leaving.size()), points_before);
  EXPECT_EQ(sw.window->num_keyframes(), 2);
  EXPECT_EQ(sw.window->num_points(), 0);
  const Eigen::MatrixXd& H_prior = sw.window->prior_hessian();
  const Eigen::VectorXd& b_prior = sw.window->prior_gradient();
  ASSERT_EQ(H_prior.rows(), 16);
  EXPECT_GT(H_exp.norm(), 1.0);
  EXPECT_LT((H_prior - H_exp).norm(), 1e-6 * H_exp.norm());
  // b comes out of a strongly cancelling sum (float Jacobians): looser.
  EXPECT_LT((b_prior - b_exp).norm(), 1e-4 * b_exp.norm());
  // The remaining keyframes now carry prior information: FEJ fixed.
  EXPECT_TRUE(sw.window->keyframe(0).fej_fixed);
  EXPECT_TRUE(sw.window->keyframe(1).fej_fixed);
  // Leaving points are reported in world coordinates at their estimated depth.
  for (const MarginalizedPoint& p : leaving) {
    const Eigen::Vector3d X_c = sw.true_world_to_camera[0] * p.world;
    EXPECT_NEAR(X_c.z(), 1.0 / p.idepth, 1e-6);
    EXPECT_GE(p.num_residuals, 0);
  }
}

// Monocular window without gauge priors: the energy is invariant to a global
// rigid motion and a global scale. The prior created by marginalisation must
// not contain information along those 7 directions (evaluated at the FEJ points).
// Information of `H` along the monocular gauge directions (global rigid
// motion: xi_i = Adj(T_i) delta; global scale: t_i -> (1 + s) t_i) at the FEJ
// points, relative to the information along a generic direction.
double GaugeInformationRatio(const Window& window, const Eigen::MatrixXd& H) {
  const int n = window.num_keyframes();
  std::vector<Eigen::VectorXd> null_directions;
  for (int k = 0; k < 6; ++k) {
    Vector6d delta = Vector6d::Zero();
    delta(k) = 1.0;
    Eigen::VectorXd v = Eigen::VectorXd::Zero(8 * n);
    for (int i = 0; i < n; ++i) v.segment<6>(8 * i) = Adjoint(window.keyframe(i).world_to_camera_fej) * delta;
    null_directions.push_back(v);
  }
  Eigen::VectorXd scale = Eigen::VectorXd::Zero(8 * n);
  for (int i = 0; i < n; ++i) scale.segment<3>(8 * i) = window.keyframe(i).world_to_camera_fej.translation();
  null_directions.push_back(scale);
  Eigen::VectorXd generic = Eigen::VectorXd::Zero(8 * n);
  generic.segment<3>(8) = Eigen::Vector3d(0.3, -0.2, 1.0);
  const double generic_info = generic.dot(H * generic) / generic.squaredNorm();
  EXPECT_GT(generic_info, 1.0);
  double worst = 0.0;
  for (const Eigen::VectorXd& v : null_directions) worst = std::max(worst, v.dot(H * v) / v.squaredNorm());
  return worst / generic_info;
}

WindowOptions NoGaugePriors() {
  WindowOptions options;
  options.first_pose_prior = 0.0;
  options.affine_a_prior = 0.0;
  options.affine_b_prior = 0.0;
  return options;
}

// Monocular window without gauge priors: the energy is invariant to a global
// rigid motion and a global scale; the marginalisation prior must not contain
// information along those 7 directions.
TEST(BackendMarginalization, PriorKeepsMonocularGaugeFreedom) {
  SceneWindowSpec spec = OneHostSpec();
  spec.num_keyframes = 4;
  auto sw = BuildSceneWindow(NoGaugePriors(), spec);
  sw.window->MarginalizeKeyframe(0);
  ASSERT_EQ(sw.window->prior_hessian().rows(), 24);
  EXPECT_LT(GaugeInformationRatio(*sw.window, sw.window->prior_hessian()), 1e-6);
}

// Two marginalisations with an optimisation in between (the estimates move
// away from the linearisation points): with first-estimate Jacobians the
// prior stays gauge-free; without them it gains spurious information.
double GaugeInformationAfterTwoMarginalizations(bool fej) {
  WindowOptions options = NoGaugePriors();
  options.first_estimate_jacobians = fej;
  SceneWindowSpec spec;
  spec.num_keyframes = 5;
  spec.num_hosts = 2;
  spec.grid_step = 20;
  spec.pose_noise_t = 0.03;
  spec.pose_noise_r = 0.005;
  spec.idepth_noise = 0.1;
  spec.seed = 9;
  auto sw = BuildSceneWindow(options, spec);
  sw.window->MarginalizeKeyframe(sw.window->keyframe(0).id);
  sw.window->Optimize(5);
  sw.window->MarginalizeKeyframe(sw.window->keyframe(0).id);
  return GaugeInformationRatio(*sw.window, sw.window->prior_hessian());
}

TEST(BackendMarginalization, FirstEstimateJacobiansKeepPriorConsistent) {
  const double with_fej = GaugeInformationAfterTwoMarginalizations(true);
  const double without_fej = GaugeInformationAfterTwoMarginalizations(false);
  EXPECT_LT(with_fej, 1e-6);
  EXPECT_GT(without_fej, 1e-4);  // the test can tell the two apart
  EXPECT_GT(without_fej, 100 * with_fej) << with_fej << " " << without_fej;
}

}  // namespace
}  // namespace dvso::vo

namespace dvso::vo {
namespace {

TEST(BackendMarginalization, KeyframeSelectionKeepsNewestAndWindowSize) {
  WindowOptions options;
  options.max_keyframes = 4;
  SceneWindowSpec spec;
  spec.num_keyframes = 5;
  spec.num_hosts = 4;
  spec.grid_step = 24;
  auto sw = testing::BuildSceneWindow(options, spec);
  const std::vector<int> ids = sw.window->KeyframesToMarginalize();
  // 5 keyframes, room for the next one with max 4: two must leave.
  ASSERT_EQ(ids.size(), 2u);
  for (int id : ids) EXPECT_NE(id, sw.window->keyframe(sw.window->num_keyframes() - 1).id);
  for (int id : ids) sw.window->MarginalizeKeyframe(id);
  EXPECT_EQ(sw.window->num_keyframes(), 3);
  EXPECT_EQ(sw.window->prior_hessian().rows(), 24);
  for (int i = 0; i < sw.window->num_keyframes(); ++i) {
    for (const Point& p : sw.window->keyframe(i).points) {
      for (const Residual& r : p.residuals) {
        EXPECT_NE(sw.window->FindKeyframe(r.target_id), nullptr) << "residual into a marginalised keyframe";
      }
    }
  }
  // The window still optimises with the prior in place.
  const OptimizationSummary s = sw.window->Optimize(3);
  EXPECT_LE(s.final_energy, s.initial_energy);
}

TEST(BackendMarginalization, DistanceScoreByHand) {
  // Camera centres on a line at x = 0, 1, 2 and the newest at 10 (world_to_camera translation = -c).
  std::vector<Eigen::Isometry3d> poses;
  for (double x : {0.0, 1.0, 2.0, 10.0}) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(-x, 0, 0);
    poses.push_back(T);
  }
  std::vector<bool> leaving(4, false);
  // sqrt(d(i, newest)) * sum over the other older keyframes (the newest is not in the sum).
  EXPECT_NEAR(MarginalizationDistanceScore(poses, leaving, 0), std::sqrt(10.0) * (1.0 + 0.5), 1e-4);
  EXPECT_NEAR(MarginalizationDistanceScore(poses, leaving, 1), 3.0 * (1.0 + 1.0), 1e-4);
  EXPECT_NEAR(MarginalizationDistanceScore(poses, leaving, 2), std::sqrt(8.0) * (0.5 + 1.0), 1e-4);
  // A keyframe already leaving no longer counts; a rotation does not change distances.
  leaving[1] = true;
  EXPECT_NEAR(MarginalizationDistanceScore(poses, leaving, 0), std::sqrt(10.0) * 0.5, 1e-4);
  poses[2].linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()).toRotationMatrix();
  poses[2].translation() = -(poses[2].linear() * Eigen::Vector3d(2, 0, 0));
  EXPECT_NEAR(MarginalizationDistanceScore(poses, leaving, 2), std::sqrt(8.0) * 0.5, 1e-4);
  EXPECT_THROW(MarginalizationDistanceScore(poses, leaving, 3), Error);  // the newest never leaves
}

TEST(BackendMarginalization, KeyframeThatLostItsPointsLeavesFirst) {
  WindowOptions options;
  SceneWindowSpec spec;
  spec.num_keyframes = 4;
  spec.num_hosts = 3;
  spec.grid_step = 24;
  auto sw = testing::BuildSceneWindow(options, spec);
  EXPECT_TRUE(sw.window->KeyframesToMarginalize().empty());  // 4 < 7: nothing to do
  sw.window->mutable_keyframes()[1].points.clear();          // lost all its points
  // DSO keeps at least setting_minFrames (5) keyframes: with 4 nothing leaves yet.
  EXPECT_TRUE(sw.window->KeyframesToMarginalize().empty());
  options.min_keyframes_kept = 3;
  sw.window->SetOptions(options);
  const std::vector<int> ids = sw.window->KeyframesToMarginalize();
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0], sw.window->keyframe(1).id);
}

TEST(BackendMarginalization, KeyframeWithFarBrightnessLeaves) {
  WindowOptions options;
  options.min_keyframes_kept = 3;
  SceneWindowSpec spec;
  spec.num_keyframes = 4;
  spec.num_hosts = 3;
  spec.grid_step = 24;
  auto sw = testing::BuildSceneWindow(options, spec);
  EXPECT_TRUE(sw.window->KeyframesToMarginalize().empty());
  sw.window->mutable_keyframes()[2].a = 1.5 * options.max_log_affine_in_window;  // e^a: far darker/brighter
  const std::vector<int> ids = sw.window->KeyframesToMarginalize();
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0], sw.window->keyframe(2).id);
}

// Regression (stereo scale run-away on long KITTI-like runs): a stereo point's
// static stereo residual never leaves the image, so without DSO's rule the
// point - and with it its keyframe - stayed in the window forever, and
// long-gone keyframes kept constraining the current ones. Points no longer
// seen by the newest keyframe must leave, carrying their information into the
// prior, so that their keyframe gets marginalised.
TEST(BackendMarginalization, StereoPointsUnseenByNewestKeyframeLeave) {
  WindowOptions options;
  options.min_keyframes_kept = 3;
  SceneWindowSpec spec;
  spec.num_keyframes = 4;
  spec.num_hosts = 3;
  spec.grid_step = 20;
  spec.stereo = true;
  auto sw = testing::BuildSceneWindow(options, spec);
  Window& w = *sw.window;
  w.Optimize(2);
  w.RemoveOutliers();
  const int newest = w.keyframe(3).id;
  const size_t host0_points = w.keyframe(0).points.size();
  const size_t host1_points = w.keyframe(1).points.size();
  ASSERT_GT(host0_points, 20u);
  ASSERT_GT(host1_points, 20u);
  // Keyframe 0's points are no longer observed by the newest keyframe (e.g.
  // they left its field of view): their residuals into it are gone.
  size_t with_stereo = 0;
  for (Point& p : w.mutable_keyframes()[0].points) {
    p.residuals.erase(std::remove_if(p.residuals.begin(), p.residuals.end(),
                                     [&](const Residual& r) { return r.target_id == newest; }),
                      p.residuals.end());
    for (const Residual& r : p.residuals) with_stereo += r.kind == ResidualKind::kStaticStereo;
  }
  ASSERT_GT(with_stereo, host0_points / 2);  // these would live on through their static stereo residual
  // A few points of keyframes 1 and 2 already left the newest image (their
  // residual into it was removed): they leave too; the others stay.
  std::vector<size_t> seen(3, 0);
  for (int h = 1; h < 3; ++h) {
    for (const Point& p : w.keyframe(h).points) {
      for (const Residual& r : p.residuals) seen[h] += r.target_id == newest;
    }
  }
  ASSERT_GT(seen[1], host1_points / 2);
  const size_t expected_leaving = w.num_points() - seen[1] - seen[2] - w.keyframe(3).points.size();
  const double prior_trace_before = w.prior_hessian().trace();
  const std::vector<MarginalizedPoint> left = w.MarginalizeInvisiblePoints();
  EXPECT_EQ(left.size(), expected_leaving);
  int from_host0 = 0;
  for (const MarginalizedPoint& m : left) from_host0 += m.host_id == w.keyframe(0).id;
  EXPECT_EQ(from_host0, static_cast<int>(host0_points));
  EXPECT_TRUE(w.keyframe(0).points.empty());
  EXPECT_EQ(w.keyframe(1).points.size(), seen[1]);
  EXPECT_EQ(w.keyframe(2).points.size(), seen[2]);
  for (int h = 1; h < 3; ++h) {
    for (const Point& p : w.keyframe(h).points) {  // the points that stay keep their residuals
      int into_newest = 0;
      for (const Residual& r : p.residuals) into_newest += r.target_id == newest;
      EXPECT_EQ(into_newest, 1);
      EXPECT_GE(p.residuals.size(), 2u);
    }
  }
  // Their information went into the prior (and fixed the linearisation points).
  EXPECT_GT(w.prior_hessian().trace(), prior_trace_before + 1.0);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(w.prior_hessian());
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-6 * eig.eigenvalues().maxCoeff());
  EXPECT_TRUE(w.keyframe(0).fej_fixed);
  // The keyframe without points now leaves first.
  const std::vector<int> ids = w.KeyframesToMarginalize();
  ASSERT_EQ(ids.size(), 1u);
  EXPECT_EQ(ids[0], w.keyframe(0).id);
  // The window still sits at the truth after optimising with the new prior
  // (the marginalised information is consistent).
  w.MarginalizeKeyframe(ids[0]);
  const OptimizationSummary s = w.Optimize(4);
  EXPECT_LE(s.final_energy, s.initial_energy);
  for (int i = 0; i < w.num_keyframes(); ++i) {
    const Keyframe& kf = w.keyframe(i);
    const int true_index = kf.id / 10;
    const Eigen::Isometry3d err = kf.world_to_camera * sw.true_world_to_camera[true_index].inverse();
    EXPECT_LT(err.translation().norm(), 0.01) << "keyframe " << kf.id;
  }
}

}  // namespace
}  // namespace dvso::vo
