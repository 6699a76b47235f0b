// Every residual kind's analytic Jacobians against central finite differences
// (host pose, target pose, affine a/b of both, inverse depth), and residual
// values against closed forms. A linear-ramp image makes bilinear
// interpolation and central-difference gradients exact, so the geometry is
// tested tightly; a smooth sinusoidal image checks that gradients are sampled
// at the right place (looser tolerance: bilinear slopes vs interpolated gradients).
#include <gtest/gtest.h>

#include "core/error.h"
#include "tests/vo/test_backend_util.h"
#include "vo/optimization/residuals.h"
#include "vo/optimization/window.h"

namespace dvso::vo {
namespace {

using testing::ImageFromFunction;
using testing::MakePyramid;
using testing::SmallCamera;
using Residuals = Eigen::Matrix<double, kPatternSize, 1>;

float Ramp(double x, double y) { return static_cast<float>(60.0 + 0.35 * x + 0.2 * y); }
float Waves(double x, double y) {
  return static_cast<float>(128.0 + 50.0 * std::sin(x / 23.0 + 0.3) * std::cos(y / 27.0) + 20.0 * std::sin((x + y) / 31.0));
}

struct Fixture {
  StereoCamera camera;
  WindowOptions options;
  std::unique_ptr<Window> window;
  int point_id = -1;
};

Eigen::Isometry3d Pose(const Eigen::Vector3d& t, const Eigen::Vector3d& w) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = ExpSO3(w);
  T.translation() = t;
  return T;
}

// The fixture's D^R map (px): steep along x, so that the virtual stereo Jacobian's (1 + dD^R/dx) = 1.4 matters.
double FixtureRightDisparity(double x, double y) { return 20.0 + 0.4 * x + 0.01 * y; }

// Two keyframes (host 0, target 1) seeing the same image function, one point.
Fixture MakeFixture(const std::function<float(double, double)>& image_fn, bool stereo, bool virtual_stereo) {
  Fixture f;
  f.camera.left = SmallCamera();
  f.camera.baseline = 0.5;
  f.options.huber_threshold = 1e6;  // keep the IRLS weights out of the way
  f.options.outlier_energy_threshold = 1e12;
  f.window = std::make_unique<Window>(f.options, f.camera);
  const cv::Mat image = ImageFromFunction(f.camera.left, image_fn);
  KeyframeInput host;
  host.id = 0;
  host.world_to_camera = Pose({0.1, -0.05, 0.2}, {0.02, -0.03, 0.01});
  host.a = 0.1;
  host.b = 3.0;
  host.left = MakePyramid(image, f.camera.left);
  if (stereo) host.right = MakePyramid(ImageFromFunction(f.camera.left, [&](double x, double y) {
                                         return image_fn(x + 7.3, y);
                                       }),
                                       f.camera.left);
  if (virtual_stereo) {
    host.right_disparity = cv::Mat(f.camera.left.height, f.camera.left.width, CV_32FC1);
    for (int y = 0; y < host.right_disparity.rows; ++y)
      for (int x = 0; x < host.right_disparity.cols; ++x)
        host.right_disparity.at<float>(y, x) = static_cast<float>(FixtureRightDisparity(x, y));
  }
  f.window->AddKeyframe(host);
  KeyframeInput target;
  target.id = 1;
  target.world_to_camera = Pose({-0.3, 0.08, -0.4}, {-0.01, 0.05, 0.02}) * host.world_to_camera;
  target.a = -0.2;
  target.b = -5.0;
  target.left = MakePyramid(image, f.camera.left);
  f.window->AddKeyframe(target);
  f.point_id = f.window->AddPoint(0, 62.3f, 187.6f, 0.25);
  EXPECT_GE(f.point_id, 0);
  return f;
}

ResidualGeometry GeometryFor(const Fixture& f, ResidualKind kind) {
  const std::vector<Keyframe>& kfs = const_cast<Window&>(*f.window).mutable_keyframes();
  switch (kind) {
    case ResidualKind::kTemporal:
      return TemporalGeometry(kfs[0], kfs[1], f.camera.left, f.options);
    case ResidualKind::kStaticStereo:
      return StaticStereoGeometry(kfs[0], f.camera, f.options);
    case ResidualKind::kVirtualStereo:
      return VirtualStereoGeometry(kfs[0], f.camera.left, f.options);
  }
  return {};
}

ResidualEvaluation Evaluate(const Fixture& f, ResidualKind kind, bool jacobians) {
  const Keyframe& host = f.window->keyframe(0);
  ResidualEvaluation ev;
  EvaluateResidual(GeometryFor(f, kind), host.points[0], host.points[0].idepth, f.options, jacobians, &ev);
  EXPECT_EQ(ev.state, ResidualState::kActive);
  return ev;
}

Residuals R(const Fixture& f, ResidualKind kind) { return Evaluate(f, kind, false).r.cast<double>(); }

// Central differences of r w.r.t. the 17 parameters [host xi, a_h, b_h, target xi, a_t, b_t, d].
Eigen::Matrix<double, kPatternSize, 17> NumericJacobian(Fixture& f, ResidualKind kind) {
  Eigen::Matrix<double, kPatternSize, 17> J;
  std::vector<Keyframe>& kfs = f.window->mutable_keyframes();
  for (int c = 0; c < 17; ++c) {
    const double eps = c == 16 ? 1e-4 : (c % 8 == 7 ? 1e-2 : 1e-3);
    Residuals r_plus, r_minus;
    for (int s = 0; s < 2; ++s) {
      const double e = s == 0 ? eps : -eps;
      const std::vector<Keyframe> saved = kfs;
      if (c == 16) {
        kfs[0].points[0].idepth += e;
      } else {
        Keyframe& kf = kfs[c / 8];
        const int k = c % 8;
        if (k < 6) {
          Vector6d xi = Vector6d::Zero();
          xi(k) = e;
          kf.world_to_camera = ExpSE3(xi) * kf.world_to_camera;  // FEJ point stays
        } else if (k == 6) {
          kf.a += e;
        } else {
          kf.b += e;
        }
      }
      (s == 0 ? r_plus : r_minus) = R(f, kind);
      kfs = saved;
    }
    J.col(c) = (r_plus - r_minus) / (2 * eps);
  }
  return J;
}

Eigen::Matrix<double, kPatternSize, 17> AnalyticJacobian(const Fixture& f, ResidualKind kind) {
  const ResidualEvaluation ev = Evaluate(f, kind, true);
  const Eigen::Isometry3d T_th =
      f.window->keyframe(1).world_to_camera * f.window->keyframe(0).world_to_camera.inverse();
  const Eigen::Matrix<double, kPatternSize, kPairParams> Jp = ev.J_pair.cast<double>();
  Eigen::Matrix<double, kPatternSize, 17> J;
  J.block<kPatternSize, 6>(0, 0) = -Jp.leftCols<6>() * Adjoint(T_th);
  J.block<kPatternSize, 2>(0, 6) = Jp.middleCols<2>(6);
  J.block<kPatternSize, 6>(0, 8) = Jp.leftCols<6>();
  J.block<kPatternSize, 2>(0, 14) = Jp.middleCols<2>(8);
  J.col(16) = ev.J_idepth.cast<double>();
  return J;
}

void ExpectClose(const Eigen::Matrix<double, kPatternSize, 17>& analytic,
                 const Eigen::Matrix<double, kPatternSize, 17>& numeric, double rel_tol, const char* what) {
  const char* names[] = {"host xi", "host a/b", "target xi", "target a/b", "idepth"};
  const int starts[] = {0, 6, 8, 14, 16};
  const int sizes[] = {6, 2, 6, 2, 1};
  for (int g = 0; g < 5; ++g) {
    const Eigen::MatrixXd A = analytic.middleCols(starts[g], sizes[g]);
    const Eigen::MatrixXd N = numeric.middleCols(starts[g], sizes[g]);
    const double scale = std::max(N.norm(), 1e-9);
    EXPECT_LT((A - N).norm(), rel_tol * scale + 1e-6) << what << ": " << names[g] << "\nanalytic\n"
                                                      << A << "\nnumeric\n"
                                                      << N;
  }
}

TEST(BackendJacobians, TemporalResidualValueMatchesClosedForm) {
  Fixture f = MakeFixture(Ramp, false, false);
  const Keyframe& h = f.window->keyframe(0);
  const Keyframe& t = f.window->keyframe(1);
  const Residuals r = R(f, ResidualKind::kTemporal);
  const Point& p = h.points[0];
  for (int k = 0; k < kPatternSize; ++k) {
    const double u = p.u + kPatternOffsets[k][0], v = p.v + kPatternOffsets[k][1];
    const Eigen::Vector3d X_h = f.camera.left.Unproject(u, v) / p.idepth;
    const Eigen::Vector2d pt = f.camera.left.Project(t.world_to_camera * (h.world_to_camera.inverse() * X_h));
    const double expected = (Ramp(pt.x(), pt.y()) - t.b) - std::exp(t.a - h.a) * (Ramp(u, v) - h.b);
    EXPECT_NEAR(r(k), expected, 2e-3) << "pattern pixel " << k;
  }
}

TEST(BackendJacobians, TemporalJacobiansMatchFiniteDifferencesOnRamp) {
  Fixture f = MakeFixture(Ramp, false, false);
  ExpectClose(AnalyticJacobian(f, ResidualKind::kTemporal), NumericJacobian(f, ResidualKind::kTemporal), 5e-3,
              "temporal/ramp");
}

TEST(BackendJacobians, TemporalJacobiansMatchFiniteDifferencesOnWaves) {
  Fixture f = MakeFixture(Waves, false, false);
  ExpectClose(AnalyticJacobian(f, ResidualKind::kTemporal), NumericJacobian(f, ResidualKind::kTemporal), 0.1,
              "temporal/waves");
}

TEST(BackendJacobians, StaticStereoDependsOnlyOnInverseDepth) {
  for (const auto& fn : {std::function<float(double, double)>(Ramp), std::function<float(double, double)>(Waves)}) {
    Fixture f = MakeFixture(fn, true, false);
    const auto numeric = NumericJacobian(f, ResidualKind::kStaticStereo);
    const auto analytic = AnalyticJacobian(f, ResidualKind::kStaticStereo);
    EXPECT_LT(numeric.leftCols<16>().norm(), 1e-6);  // no pose / affine dependence
    EXPECT_EQ(analytic.leftCols<16>().norm(), 0.0);
    EXPECT_GT(numeric.col(16).norm(), 1.0);
    EXPECT_LT((analytic.col(16) - numeric.col(16)).norm(), 0.1 * numeric.col(16).norm()) << analytic.col(16).transpose() << "\n" << numeric.col(16).transpose();
  }
}

TEST(BackendJacobians, StaticStereoValueMatchesClosedForm) {
  Fixture f = MakeFixture(Ramp, true, false);
  const Point& p = f.window->keyframe(0).points[0];
  const Residuals r = R(f, ResidualKind::kStaticStereo);
  for (int k = 0; k < kPatternSize; ++k) {
    const double u = p.u + kPatternOffsets[k][0], v = p.v + kPatternOffsets[k][1];
    const double u_right = u - f.camera.left.fx * f.camera.baseline * p.idepth;
    EXPECT_NEAR(r(k), Ramp(u_right + 7.3, v) - Ramp(u, v), 2e-3);
  }
}

// A right camera with another gain and black level: r = (I_R(u') - bias) - gain * I_L(u)
// (vo/frame/stereo_brightness.h); the inverse depth stays the only parameter.
TEST(BackendJacobians, StaticStereoFollowsTheRightCamerasBrightnessTransfer) {
  const StereoBrightness transfer{1.2, 5.0};
  Fixture f = MakeFixture(Ramp, true, false);
  f.window->SetRightBrightness(0, transfer);
  const Point& p = f.window->keyframe(0).points[0];
  const Residuals r = R(f, ResidualKind::kStaticStereo);
  for (int k = 0; k < kPatternSize; ++k) {
    const double u = p.u + kPatternOffsets[k][0], v = p.v + kPatternOffsets[k][1];
    const double u_right = u - f.camera.left.fx * f.camera.baseline * p.idepth;
    EXPECT_NEAR(r(k), (Ramp(u_right + 7.3, v) - transfer.bias) - transfer.gain * Ramp(u, v), 3e-3);
  }
  Fixture w = MakeFixture(Waves, true, false);
  w.window->SetRightBrightness(0, transfer);
  const auto numeric = NumericJacobian(w, ResidualKind::kStaticStereo);
  const auto analytic = AnalyticJacobian(w, ResidualKind::kStaticStereo);
  EXPECT_LT(numeric.leftCols<16>().norm(), 1e-6);
  EXPECT_EQ(analytic.leftCols<16>().norm(), 0.0);
  EXPECT_LT((analytic.col(16) - numeric.col(16)).norm(), 0.1 * numeric.col(16).norm());
  EXPECT_THROW(w.window->SetRightBrightness(0, StereoBrightness{0.0, 0.0}), Error);
  // With a radial term the gain is gain * (1 + radial rho^2) at each host pattern pixel; the Jacobians
  // do not change (the scale depends on no parameter).
  const StereoBrightness radial{1.2, 5.0, 0.3};
  f.window->SetRightBrightness(0, radial);
  const Residuals rr = R(f, ResidualKind::kStaticStereo);
  const PinholeCamera& c = f.camera.left;
  const double corner_sq = (static_cast<double>(c.width) * c.width + static_cast<double>(c.height) * c.height) / 4;
  for (int k = 0; k < kPatternSize; ++k) {
    const double u = p.u + kPatternOffsets[k][0], v = p.v + kPatternOffsets[k][1];
    const double rho_sq = ((u - c.cx) * (u - c.cx) + (v - c.cy) * (v - c.cy)) / corner_sq;  // by hand
    const double u_right = u - f.camera.left.fx * f.camera.baseline * p.idepth;
    const double expected = (Ramp(u_right + 7.3, v) - radial.bias) - radial.gain * (1 + 0.3 * rho_sq) * Ramp(u, v);
    EXPECT_NEAR(rr(k), expected, 3e-3);
    EXPECT_GT(std::abs(rr(k) - r(k)), 0.3 * rho_sq * 1.2 * Ramp(u, v) - 0.01);  // the term is used
  }
  w.window->SetRightBrightness(0, radial);
  const auto numeric_radial = NumericJacobian(w, ResidualKind::kStaticStereo);
  const auto analytic_radial = AnalyticJacobian(w, ResidualKind::kStaticStereo);
  EXPECT_LT((analytic_radial.col(16) - numeric_radial.col(16)).norm(), 0.1 * numeric_radial.col(16).norm());
  EXPECT_THROW(w.window->SetRightBrightness(0, StereoBrightness{1.0, 0.0, -1.5}), Error);
}

TEST(BackendJacobians, VirtualStereoValueMatchesEq58) {
  Fixture f = MakeFixture(Ramp, false, true);
  const Point& p = f.window->keyframe(0).points[0];
  const Residuals r = R(f, ResidualKind::kVirtualStereo);
  for (int k = 0; k < kPatternSize; ++k) {
    const double u = p.u + kPatternOffsets[k][0], v = p.v + kPatternOffsets[k][1];
    const double u_dagger = u - f.camera.left.fx * f.options.virtual_stereo_baseline * p.idepth;
    const double disparity = FixtureRightDisparity(u_dagger, v);
    EXPECT_NEAR(r(k), Ramp(u_dagger + disparity, v) - Ramp(u, v), 2e-3);
  }
}

// Points sit on integer rows and the virtual right camera keeps the row, so the bilinear sample of D^R
// gives the row below weight 0: an invalid pixel there (a file map's hole, a NaN) must not remove the
// residual. Row v + 3 is below every pattern row (offsets -2..2) and used by none.
TEST(BackendJacobians, VirtualStereoIgnoresAnInvalidRowItsSampleGivesNoWeight) {
  Fixture f = MakeFixture(Ramp, false, true);
  const int id = f.window->AddPoint(0, 62.0f, 187.0f, 0.25);
  ASSERT_GE(id, 0);
  cv::Mat& disparity = f.window->mutable_keyframes()[0].right_disparity;
  disparity.row(190).setTo(0.0f);
  const Keyframe& host = f.window->keyframe(0);
  const Point& p = host.points.back();
  ResidualEvaluation ev;
  EvaluateResidual(GeometryFor(f, ResidualKind::kVirtualStereo), p, p.idepth, f.options, false, &ev);
  ASSERT_EQ(ev.state, ResidualState::kActive);
  for (int k = 0; k < kPatternSize; ++k) {
    const double u = p.u + kPatternOffsets[k][0], v = p.v + kPatternOffsets[k][1];
    const double u_dagger = u - f.camera.left.fx * f.options.virtual_stereo_baseline * p.idepth;
    EXPECT_NEAR(ev.r(k), Ramp(u_dagger + FixtureRightDisparity(u_dagger, v), v) - Ramp(u, v), 2e-3);
  }
  // A pattern row itself invalid still removes it.
  disparity.row(189).setTo(0.0f);
  EvaluateResidual(GeometryFor(f, ResidualKind::kVirtualStereo), p, p.idepth, f.options, false, &ev);
  EXPECT_NE(ev.state, ResidualState::kActive);
}

TEST(BackendJacobians, CouplingWeightsScaleTheEnergyButNotTheOutlierTest) {
  Fixture f = MakeFixture(Ramp, true, true);
  const Point& p = f.window->keyframe(0).points[0];
  const double idepth = 1.1 * p.idepth;  // off the true depth: the residuals are not zero
  const WindowOptions original = f.options;
  for (const ResidualKind kind : {ResidualKind::kStaticStereo, ResidualKind::kVirtualStereo}) {
    ResidualEvaluation unit;
    EvaluateResidual(GeometryFor(f, kind), p, idepth, f.options, false, &unit);
    ASSERT_EQ(unit.state, ResidualState::kActive);
    ASSERT_GT(unit.energy, 0.0f);
    // A threshold at twice this residual's energy per pattern pixel: it is an inlier at weight 1 ...
    f.options.outlier_energy_threshold = 2.0 * unit.energy / kPatternSize;
    // ... and stays one at weight 4 (mu or lambda), where its energy counts 4 times.
    f.options.static_stereo_weight = f.options.virtual_stereo_weight = 4.0;
    ResidualEvaluation heavy;
    EvaluateResidual(GeometryFor(f, kind), p, idepth, f.options, false, &heavy);
    EXPECT_NEAR(heavy.energy, 4.0f * unit.energy, 1e-3f * unit.energy) << static_cast<int>(kind);
    EXPECT_EQ(heavy.state, ResidualState::kActive) << static_cast<int>(kind);
    // The energy an out-of-bounds residual counts with across an LM step is the largest one an active
    // residual of its kind can have: weighted too, or worsening such a residual would look free.
    EXPECT_FLOAT_EQ(CappedResidualEnergy(f.options, kind), 4.0f * CappedResidualEnergy(f.options, ResidualKind::kTemporal));
    EXPECT_LE(heavy.energy, CappedResidualEnergy(f.options, kind));
    f.options = original;
  }
}

TEST(BackendJacobians, VirtualStereoJacobianMatchesFiniteDifferences) {
  for (const auto& fn : {std::function<float(double, double)>(Ramp), std::function<float(double, double)>(Waves)}) {
    Fixture f = MakeFixture(fn, false, true);
    const auto numeric = NumericJacobian(f, ResidualKind::kVirtualStereo);
    const auto analytic = AnalyticJacobian(f, ResidualKind::kVirtualStereo);
    EXPECT_LT(numeric.leftCols<16>().norm(), 1e-6);
    EXPECT_EQ(analytic.leftCols<16>().norm(), 0.0);
    EXPECT_GT(numeric.col(16).norm(), 1.0);
    // Tight enough that the chain-rule factor (1 + dD^R/dx) = 1.4 of eq. 5.8's Jacobian cannot be dropped.
    EXPECT_LT((analytic.col(16) - numeric.col(16)).norm(), 0.03 * numeric.col(16).norm());
  }
}

}  // namespace
}  // namespace dvso::vo
