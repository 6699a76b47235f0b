// Umeyama alignment: exact recovery of known SE(3)/Sim(3) transforms,
// agreement with Eigen's implementation on noisy data, and error cases.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "core/alignment.h"
#include "core/error.h"
#include "core/lie.h"

namespace dvso {
namespace {

std::vector<Eigen::Vector3d> RandomPoints(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-20.0, 20.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) points.emplace_back(uniform(rng), uniform(rng), uniform(rng));
  return points;
}

Similarity3 KnownSim3() {
  Similarity3 s;
  s.scale = 2.5;
  s.rotation = ExpSO3(Eigen::Vector3d(0.3, -1.2, 0.7));
  s.translation = Eigen::Vector3d(4.0, -3.0, 12.0);
  return s;
}

TEST(Alignment, Sim3RecoversKnownTransform) {
  const Similarity3 truth = KnownSim3();
  const auto source = RandomPoints(50, 1);
  std::vector<Eigen::Vector3d> target;
  for (const auto& p : source) target.push_back(truth * p);
  const Similarity3 found = UmeyamaAlignment(source, target, AlignmentMode::kSim3);
  EXPECT_NEAR(found.scale, 2.5, 1e-10);
  EXPECT_LT((found.rotation - truth.rotation).norm(), 1e-10);
  EXPECT_LT((found.translation - truth.translation).norm(), 1e-9);
}

TEST(Alignment, Se3RecoversRigidTransformWithUnitScale) {
  Similarity3 truth = KnownSim3();
  truth.scale = 1.0;
  const auto source = RandomPoints(20, 2);
  std::vector<Eigen::Vector3d> target;
  for (const auto& p : source) target.push_back(truth * p);
  const Similarity3 found = UmeyamaAlignment(source, target, AlignmentMode::kSE3);
  EXPECT_DOUBLE_EQ(found.scale, 1.0);
  EXPECT_LT((found.rotation - truth.rotation).norm(), 1e-10);
  EXPECT_LT((found.translation - truth.translation).norm(), 1e-9);
}

TEST(Alignment, Se3DoesNotAbsorbScale) {
  // Target is the source scaled by 2 about the origin: SE(3) must keep s = 1,
  // leaving a residual, while Sim(3) explains it exactly.
  const auto source = RandomPoints(30, 3);
  std::vector<Eigen::Vector3d> target;
  for (const auto& p : source) target.push_back(2.0 * p);
  const Similarity3 se3 = UmeyamaAlignment(source, target, AlignmentMode::kSE3);
  const Similarity3 sim3 = UmeyamaAlignment(source, target, AlignmentMode::kSim3);
  double se3_residual = 0.0, sim3_residual = 0.0;
  for (size_t i = 0; i < source.size(); ++i) {
    se3_residual += (target[i] - se3 * source[i]).squaredNorm();
    sim3_residual += (target[i] - sim3 * source[i]).squaredNorm();
  }
  EXPECT_GT(se3_residual, 1.0);
  EXPECT_LT(sim3_residual, 1e-12);
  EXPECT_NEAR(sim3.scale, 2.0, 1e-12);
}

TEST(Alignment, MatchesEigenUmeyamaOnNoisyData) {
  const Similarity3 truth = KnownSim3();
  const auto source = RandomPoints(40, 4);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.5);
  std::vector<Eigen::Vector3d> target;
  Eigen::Matrix3Xd src(3, source.size()), dst(3, source.size());
  for (size_t i = 0; i < source.size(); ++i) {
    target.push_back(truth * source[i] + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    src.col(i) = source[i];
    dst.col(i) = target[i];
  }
  const Eigen::Matrix4d reference = Eigen::umeyama(src, dst, true);
  const Similarity3 found = UmeyamaAlignment(source, target, AlignmentMode::kSim3);
  Eigen::Matrix4d ours = Eigen::Matrix4d::Identity();
  ours.topLeftCorner<3, 3>() = found.scale * found.rotation;
  ours.topRightCorner<3, 1>() = found.translation;
  EXPECT_LT((ours - reference).norm(), 1e-9);
}

TEST(Alignment, ReflectionIsNeverReturned) {
  // A mirrored target: the best proper rotation must still have det = +1.
  const auto source = RandomPoints(25, 6);
  std::vector<Eigen::Vector3d> target;
  for (const auto& p : source) target.emplace_back(-p.x(), p.y(), p.z());
  const Similarity3 found = UmeyamaAlignment(source, target, AlignmentMode::kSim3);
  EXPECT_NEAR(found.rotation.determinant(), 1.0, 1e-12);
}

TEST(Alignment, ApplyMovesPoseCentreAndRotatesOrientation) {
  const Similarity3 s = KnownSim3();
  Eigen::Isometry3d pose = ExpSE3((Vector6d() << 1, 2, 3, 0.1, 0.2, 0.3).finished());
  const Eigen::Isometry3d moved = s.Apply(pose);
  EXPECT_LT((moved.translation() - s * pose.translation()).norm(), 1e-12);
  EXPECT_LT((moved.linear() - s.rotation * pose.linear()).norm(), 1e-12);
}

TEST(Alignment, NoneIsIdentity) {
  const auto source = RandomPoints(2, 7);
  const Similarity3 found = UmeyamaAlignment(source, RandomPoints(2, 8), AlignmentMode::kNone);
  EXPECT_EQ(found.scale, 1.0);
  EXPECT_TRUE(found.rotation.isIdentity());
  EXPECT_TRUE(found.translation.isZero());
}

TEST(Alignment, RejectsBadInput) {
  const auto points = RandomPoints(10, 9);
  EXPECT_THROW(UmeyamaAlignment(points, RandomPoints(9, 9), AlignmentMode::kSE3), Error);
  EXPECT_THROW(UmeyamaAlignment(RandomPoints(2, 1), RandomPoints(2, 2), AlignmentMode::kSim3), Error);
  const std::vector<Eigen::Vector3d> same(5, Eigen::Vector3d(1, 2, 3));
  EXPECT_THROW(UmeyamaAlignment(same, RandomPoints(5, 3), AlignmentMode::kSim3), Error);
}

TEST(Alignment, ParsesModeNames) {
  EXPECT_EQ(ParseAlignmentMode("none"), AlignmentMode::kNone);
  EXPECT_EQ(ParseAlignmentMode("SE3"), AlignmentMode::kSE3);
  EXPECT_EQ(ParseAlignmentMode("sim3"), AlignmentMode::kSim3);
  EXPECT_THROW(ParseAlignmentMode("affine"), Error);
  EXPECT_EQ(AlignmentModeName(AlignmentMode::kSim3), "sim3");
}

}  // namespace
}  // namespace dvso
