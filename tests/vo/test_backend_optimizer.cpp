// Convergence of the windowed bundle adjustment on rendered views of a
// textured plane scene with known poses: from perturbed poses and inverse
// depths back to the truth; static or virtual stereo residuals fix the scale.
#include <gtest/gtest.h>

#include <set>

#include "tests/vo/test_backend_util.h"
#include "vo/optimization/accumulator.h"
#include "vo/optimization/window.h"

namespace dvso::vo {
namespace {

using testing::BuildSceneWindow;
using testing::SceneWindow;
using testing::SceneWindowSpec;

struct Errors {
  double max_translation = 0.0;  // metres, camera centres
  double max_rotation = 0.0;     // radians
  double median_idepth_rel = 0.0;
};

// Errors of the window state vs the truth; `scale` multiplies estimated
// translations (to compare a monocular result up to scale).
Errors ComputeErrors(const SceneWindow& sw, double scale = 1.0) {
  Errors e;
  for (int i = 0; i < sw.window->num_keyframes(); ++i) {
    const Eigen::Isometry3d est = sw.window->keyframe(i).world_to_camera.inverse();
    const Eigen::Isometry3d gt = sw.true_world_to_camera[i].inverse();
    e.max_translation = std::max(e.max_translation, (scale * est.translation() - gt.translation()).norm());
    e.max_rotation = std::max(e.max_rotation, RotationAngle(est.linear().transpose() * gt.linear()));
  }
  std::vector<double> rel;
  for (int i = 0; i < sw.window->num_keyframes(); ++i) {
    for (const Point& p : sw.window->keyframe(i).points) {
      const double d = sw.true_idepth.at(p.id);
      rel.push_back(std::abs(p.idepth / scale - d) / d);
    }
  }
  std::nth_element(rel.begin(), rel.begin() + rel.size() / 2, rel.end());
  e.median_idepth_rel = rel[rel.size() / 2];
  return e;
}

// Least-squares scale of the estimated camera centres onto the true ones.
double AlignScale(const SceneWindow& sw) {
  double num = 0.0, den = 0.0;
  for (int i = 1; i < sw.window->num_keyframes(); ++i) {
    const Eigen::Vector3d est = sw.window->keyframe(i).world_to_camera.inverse().translation();
    const Eigen::Vector3d gt = sw.true_world_to_camera[i].inverse().translation();
    num += est.dot(gt);
    den += est.dot(est);
  }
  return num / den;
}

SceneWindowSpec PerturbedSpec() {
  SceneWindowSpec spec;
  spec.num_keyframes = 4;
  spec.num_hosts = 3;
  spec.grid_step = 10;
  spec.pose_noise_t = 0.04;
  spec.pose_noise_r = 0.006;
  spec.idepth_noise = 0.15;
  spec.seed = 11;
  return spec;
}

TEST(BackendOptimizer, MonoConvergesUpToScale) {
  WindowOptions options;
  auto sw = BuildSceneWindow(options, PerturbedSpec());
  ASSERT_GT(sw.window->num_points(), 300);
  const Errors before = ComputeErrors(sw, AlignScale(sw));
  const OptimizationSummary s = sw.window->Optimize(30);
  EXPECT_LT(s.final_energy, s.initial_energy);
  EXPECT_GT(s.accepted_steps, 0);
  const Errors after = ComputeErrors(sw, AlignScale(sw));
  // Monocular: the energy minimum itself sits a few mm from the truth here
  // (bilinear interpolation of the rendered texture), and the window is short
  // (1 m of motion), so the tolerances are looser than with stereo.
  EXPECT_GT(before.max_translation, 0.04);
  EXPECT_LT(after.max_translation, 0.015);
  EXPECT_LT(after.max_rotation, 0.002);
  EXPECT_LT(after.median_idepth_rel, 0.03);
  // The first keyframe (gauge prior, weight 1e8) moves only negligibly.
  EXPECT_LT((sw.window->keyframe(0).world_to_camera.matrix() - sw.true_world_to_camera[0].matrix()).norm(), 1e-4);
}

TEST(BackendOptimizer, StaticStereoFixesMetricScale) {
  WindowOptions options;
  SceneWindowSpec spec = PerturbedSpec();
  spec.stereo = true;
  spec.scale = 1.25;  // a monocularly consistent but wrong scale
  auto sw = BuildSceneWindow(options, spec);
  const Errors before = ComputeErrors(sw);
  sw.window->Optimize(30);
  const Errors after = ComputeErrors(sw);  // no scale alignment
  // Per-point information: stereo adds to the temporal part.
  double total = 0.0, temporal = 0.0;
  for (const Point& p : sw.window->keyframe(0).points) {
    EXPECT_GE(p.idepth_hessian, p.idepth_hessian_temporal);
    EXPECT_GE(p.idepth_hessian_temporal, 0.0f);
    total += p.idepth_hessian;
    temporal += p.idepth_hessian_temporal;
  }
  EXPECT_GT(temporal, 0.0);
  EXPECT_GT(total, 1.1 * temporal);
  EXPECT_GT(before.max_translation, 0.2);
  EXPECT_LT(after.max_translation, 0.01);
  EXPECT_LT(after.max_rotation, 0.001);
  EXPECT_LT(after.median_idepth_rel, 0.02);
}

TEST(BackendOptimizer, VirtualStereoFixesMetricScale) {
  WindowOptions options;
  options.virtual_stereo_baseline = 0.5;  // the baseline of the rendered D^R
  SceneWindowSpec spec = PerturbedSpec();
  spec.virtual_stereo = true;
  spec.scale = 1.25;
  auto sw = BuildSceneWindow(options, spec);
  sw.window->Optimize(30);
  const Errors after = ComputeErrors(sw);
  EXPECT_LT(after.max_translation, 0.015);
  EXPECT_LT(after.max_rotation, 0.001);
  EXPECT_LT(after.median_idepth_rel, 0.03);
}

TEST(BackendOptimizer, MonoWithoutStereoKeepsWrongScale) {
  // Control for the two tests above: without stereo terms the (gauge) scale
  // is not observable, so a scaled start stays scaled.
  WindowOptions options;
  SceneWindowSpec spec = PerturbedSpec();
  spec.scale = 1.25;
  auto sw = BuildSceneWindow(options, spec);
  sw.window->Optimize(30);
  EXPECT_GT(ComputeErrors(sw).max_translation, 0.1);
  EXPECT_LT(ComputeErrors(sw, AlignScale(sw)).max_translation, 0.03);
}

// A rejected step restores the state, and with it each point's H_dd (idepth_hessian), which the trial
// linearisation had overwritten with the information of the state that was thrown away.
TEST(BackendOptimizer, RejectedStepsLeaveTheDepthInformationOfTheKeptState) {
  WindowOptions options;
  // Inverse depths clamped to at least 20 (5 cm): the window starts there, and every step that the
  // clamp leaves is worse than the start (measured: no step accepted), so each trial is rejected.
  options.min_idepth = 20.0;
  auto sw = BuildSceneWindow(options, PerturbedSpec());
  std::vector<Keyframe> expected = sw.window->mutable_keyframes();  // a copy
  std::vector<PointRef> refs;
  for (int h = 0; h < static_cast<int>(expected.size()); ++h)
    for (int i = 0; i < static_cast<int>(expected[h].points.size()); ++i) refs.push_back({h, i});
  WindowLinearizer(&expected, sw.window->camera(), options).Linearize(refs);  // H_dd of the start state
  const OptimizationSummary summary = sw.window->Optimize(3);
  ASSERT_EQ(summary.accepted_steps, 0);
  int compared = 0;
  for (const PointRef& r : refs) {
    const Point& kept = sw.window->keyframe(r.host_index).points[r.point_index];
    const Point& start = expected[r.host_index].points[r.point_index];
    ASSERT_EQ(kept.idepth, start.idepth);
    EXPECT_FLOAT_EQ(kept.idepth_hessian, start.idepth_hessian);
    EXPECT_FLOAT_EQ(kept.idepth_hessian_temporal, start.idepth_hessian_temporal);
    compared += start.idepth_hessian > 0;
  }
  EXPECT_GT(compared, 100);
}

TEST(BackendOptimizer, RemoveOutliersDropsCorruptedPoints) {
  WindowOptions options;
  SceneWindowSpec spec = PerturbedSpec();
  spec.pose_noise_t = 0.0;
  spec.pose_noise_r = 0.0;
  spec.idepth_noise = 0.0;
  auto sw = BuildSceneWindow(options, spec);
  // Corrupt a few points' depths grossly: their residuals become outliers.
  std::vector<int> corrupted;
  Keyframe& host = sw.window->mutable_keyframes()[0];
  for (size_t i = 0; i < host.points.size(); i += 10) {
    host.points[i].idepth *= 3.0;
    corrupted.push_back(host.points[i].id);
  }
  const int before = sw.window->num_points();
  const int removed = sw.window->RemoveOutliers();
  EXPECT_GT(removed, static_cast<int>(corrupted.size()) / 2);
  EXPECT_LT(removed, before / 5);
  for (const Point& p : sw.window->keyframe(0).points) {
    for (const Residual& r : p.residuals) EXPECT_EQ(r.state, ResidualState::kActive);
  }
}

TEST(BackendOptimizer, RemoveOutliersKeepsTheRejectedStereoEnergyOfSurvivingPoints) {
  // Keyframe 0's right image is replaced by a black one: every static stereo residual it hosts
  // becomes an outlier while the temporal ones (exact poses and depths) stay active. The points
  // survive on their temporal residuals and must remember how badly they matched on the pair
  // (the labels' stereo-energy filters read it, sdso_labels/label_writer.h).
  WindowOptions options;
  SceneWindowSpec spec;
  spec.stereo = true;
  auto sw = BuildSceneWindow(options, spec);
  Keyframe& host = sw.window->mutable_keyframes()[0];
  std::set<int> with_stereo;  // points whose static stereo residual fits the image (not out of bounds)
  for (const Point& p : host.points) {
    for (const Residual& r : p.residuals) {
      if (r.kind == ResidualKind::kStaticStereo && r.state == ResidualState::kActive) with_stereo.insert(p.id);
    }
  }
  host.right = testing::MakePyramid(cv::Mat(sw.camera.left.height, sw.camera.left.width, CV_32FC1, cv::Scalar(0.f)),
                                    sw.camera.left);
  sw.window->Optimize(2);  // evaluates every residual with the new image (as after each keyframe)
  sw.window->RemoveOutliers();
  const float outlier_energy = kPatternSize * static_cast<float>(options.outlier_energy_threshold);
  int survivors = 0, remembered = 0;
  for (const Point& p : sw.window->keyframe(0).points) {
    for (const Residual& r : p.residuals) EXPECT_NE(r.kind, ResidualKind::kStaticStereo);
    if (with_stereo.count(p.id) == 0) continue;
    ++survivors;
    if (p.rejected_stereo_energy > outlier_energy) ++remembered;
  }
  // A few points' stereo patterns leave the image while the two iterations move their depths
  // (out of bounds is not an outlier); every other survivor remembers its rejected match.
  EXPECT_GT(survivors, 50);
  EXPECT_GE(remembered, 0.9 * survivors) << remembered << " of " << survivors;
  // Keyframe 1's pair is intact: its points keep their stereo residual and reject nothing.
  for (const Point& p : sw.window->keyframe(1).points) EXPECT_EQ(p.rejected_stereo_energy, -1.0f);
}

}  // namespace
}  // namespace dvso::vo
