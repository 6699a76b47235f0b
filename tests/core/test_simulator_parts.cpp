// Unit tests of the simulator's building blocks: mip-mapped texture lookups,
// the street path (road height, zones, revisit merging, altitude reconciliation) and sun shadows.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/simulator_path.h"
#include "core/simulator_shadows.h"
#include "core/simulator_textures.h"

namespace dvso::sim {
namespace {

TEST(HorizontalGrid, VisitsEveryPointWithinACellSizeIgnoresHeightAndStopsWhenAsked) {
  // Camera y down: the horizontal plane is x-z. Points on a 1 m lattice around the origin, also at
  // negative cells, with heights that must not matter.
  const double cell = 5.0;
  HorizontalGrid grid(Eigen::Vector3d::UnitY(), cell);
  std::vector<Eigen::Vector3d> points;
  for (int x = -20; x <= 20; ++x)
    for (int z = -20; z <= 20; ++z) {
      points.emplace_back(x, 7.0 * ((x + z) % 3), z);
      grid.Insert(points.back(), static_cast<int>(points.size()) - 1);
    }
  for (const Eigen::Vector3d& q : {Eigen::Vector3d(0.3, 0, -0.2), Eigen::Vector3d(-13.7, -40, 9.1)}) {
    std::vector<int> visited;
    EXPECT_FALSE(grid.AnyNear(q, [&](int i) {
      visited.push_back(i);
      return false;
    }));
    std::sort(visited.begin(), visited.end());
    EXPECT_TRUE(std::adjacent_find(visited.begin(), visited.end()) == visited.end());  // each once
    int within = 0;
    for (int i = 0; i < static_cast<int>(points.size()); ++i) {
      const Eigen::Vector3d d = points[i] - q;
      if (std::hypot(d.x(), d.z()) > cell) continue;
      ++within;
      EXPECT_TRUE(std::binary_search(visited.begin(), visited.end(), i)) << "point " << i << " missed";
    }
    EXPECT_GT(within, 70);
    // Nothing outside the 3x3 cells around q's cell: less than two cells away along each axis.
    for (int i : visited) {
      const Eigen::Vector3d d = points[i] - q;
      EXPECT_LT(std::max(std::abs(d.x()), std::abs(d.z())), 2 * cell);
    }
    // Stops at the first point visit accepts.
    int calls = 0;
    EXPECT_TRUE(grid.AnyNear(q, [&](int) { return ++calls == 3; }));
    EXPECT_EQ(calls, 3);
  }
  EXPECT_THROW(HorizontalGrid(Eigen::Vector3d::UnitY(), 0.0), Error);
}

// The street path's nearest-sample searches keep the first of equally near samples, so the worlds depend on the
// visiting order: the 3x3 cells along the first horizontal axis (down.unitOrthogonal()) in the outer loop, the
// second (down x first) in the inner one, each cell's points in insertion order.
TEST(HorizontalGrid, VisitsCellsInAFixedOrderAndPointsInInsertionOrder) {
  const Eigen::Vector3d down = Eigen::Vector3d(0.1, 1.0, -0.2).normalized();
  const Eigen::Vector3d axis_a = down.unitOrthogonal(), axis_b = down.cross(axis_a);
  const double cell = 2.0;
  HorizontalGrid grid(down, cell);
  const Eigen::Vector3d q = 0.7 * axis_a - 3.1 * axis_b + 5.0 * down;
  struct Inserted {
    int a, b, index;
  };
  std::vector<Inserted> inserted;
  int index = 0;
  for (int round = 0; round < 2; ++round)  // two points per cell, the cells in a scrambled order
    for (int k = 0; k < 9; ++k) {
      const int da = (k * 4) % 9 / 3 - 1, db = (k * 4) % 3 - 1;
      const Eigen::Vector3d p = q + cell * (da * axis_a + db * axis_b) + 0.1 * round * axis_b - 2.0 * round * down;
      grid.Insert(p, index);
      inserted.push_back({static_cast<int>(std::floor(p.dot(axis_a) / cell)),
                          static_cast<int>(std::floor(p.dot(axis_b) / cell)), index});
      ++index;
    }
  std::stable_sort(inserted.begin(), inserted.end(),
                   [](const Inserted& x, const Inserted& y) { return std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b); });
  std::vector<int> expected, visited;
  for (const Inserted& i : inserted) expected.push_back(i.index);
  grid.AnyNear(q, [&](int i) {
    visited.push_back(i);
    return false;
  });
  EXPECT_EQ(visited, expected);
}

TEST(SimulatorTexture, BilinearAndMipLevelsByHand) {
  // 4x4 texture: value = x (column index) / 4.
  std::vector<float> texels(16);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 4; ++x) texels[y * 4 + x] = x / 4.f;
  const MipTexture t(texels, 4);
  ASSERT_EQ(t.num_levels(), 3);  // 4x4, 2x2, 1x1
  EXPECT_FLOAT_EQ(t.mean(), (0 + 0.25f + 0.5f + 0.75f) / 4);
  // Texel centres sit at +0.5: x = 1.5 is exactly texel 1, x = 2.0 halfway between texels 1 and 2.
  EXPECT_FLOAT_EQ(t.Bilinear(0, 1.5f, 0.5f), 0.25f);
  EXPECT_FLOAT_EQ(t.Bilinear(0, 2.0f, 3.5f), 0.375f);
  // Wrap-around between the last and the first texel.
  EXPECT_FLOAT_EQ(t.Bilinear(0, 4.0f, 0.5f), 0.375f);
  // Level 1 averages 2x2 blocks: columns (0, 0.25) -> 0.125 and (0.5, 0.75) -> 0.625.
  EXPECT_FLOAT_EQ(t.Bilinear(1, 0.5f, 0.5f), 0.125f);
  // A footprint covering the whole tile returns the mean, in any direction.
  EXPECT_NEAR(t.Sample(0.3, 0.7, 64.f), t.mean(), 1e-6);
  EXPECT_NEAR(t.SampleAniso(0.3, 0.7, 16.f, 0.f, 0.f, 16.f, 4), t.mean(), 1e-6);
}

TEST(SimulatorTexture, AnisotropicFilterKeepsDetailAcrossTheMajorAxis) {
  // Stripes along v (value depends on u only, period 2 texels at 64 px).
  const int n = 64;
  std::vector<float> texels(n * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) texels[y * n + x] = (x / 8) % 2 ? 1.f : 0.f;  // 8-texel stripes
  const MipTexture t(texels, n);
  // Footprint: 1 texel across the stripes (u), 16 texels along them (v).
  const float du = 1.f / n, dv = 16.f / n;
  const float aniso_dark = t.SampleAniso(4.0 / n, 0.5, du, 0.f, 0.f, dv, 8);
  const float aniso_bright = t.SampleAniso(12.0 / n, 0.5, du, 0.f, 0.f, dv, 8);
  EXPECT_NEAR(aniso_dark, 0.f, 0.05f);
  EXPECT_NEAR(aniso_bright, 1.f, 0.05f);
  // An isotropic filter of the major axis blurs the stripes to grey.
  EXPECT_NEAR(t.Sample(4.0 / n, 0.5, 16.f), 0.5f, 0.1f);
}

TEST(SimulatorTexture, BankIsDeterministicPerSeed) {
  const TextureBank a(5, 64), b(5, 64), c(6, 64);
  EXPECT_EQ(a[kTexAsphalt].Sample(0.3, 0.4, 1.f), b[kTexAsphalt].Sample(0.3, 0.4, 1.f));
  EXPECT_NE(a[kTexAsphalt].Sample(0.3, 0.4, 1.f), c[kTexAsphalt].Sample(0.3, 0.4, 1.f));
  for (int id = 0; id < kNumTextures; ++id) {
    EXPECT_GT(a[id].mean(), 0.f) << id;
    EXPECT_LE(a[id].mean(), 1.f) << id;
  }
}

// Mean absolute difference of horizontally neighbouring texels and standard deviation of mip level `level`.
std::pair<double, double> TexelDetail(const MipTexture& t, int level) {
  const int n = t.size() >> level;
  double gradient = 0, sum = 0, sum2 = 0;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const double v = t.Bilinear(level, x + 0.5f, y + 0.5f);
      gradient += std::fabs(t.Bilinear(level, x + 1.5f, y + 0.5f) - v);
      sum += v;
      sum2 += v * v;
    }
  const double count = static_cast<double>(n) * n, mean = sum / count;
  return {gradient / count, std::sqrt(std::max(0.0, sum2 / count - mean * mean))};
}

TEST(SimulatorTexture, DetailedCarPaintCarriesTextureThePlainPaintLacks) {
  // The detailed paint must give close cars something to match on: several times the plain paint's
  // contrast and more detail at the scale a camera sees it (mip level 2 of 512 texels per 2 m: 1.6 cm, about a
  // pixel at 5 m in KITTI's camera; level 0 is dominated by the plain paint's per-texel noise), at a similar mean
  // albedo (car colours keep their brightness).
  const TextureBank bank(3, 512);
  const auto plain = TexelDetail(bank[kTexCarPaint], 2), detailed = TexelDetail(bank[kTexCarPaintDetailed], 2);
  std::printf("car paint: plain gradient %.4f std %.3f mean %.3f; detailed gradient %.4f std %.3f mean %.3f\n",
              plain.first, plain.second, bank[kTexCarPaint].mean(), detailed.first, detailed.second,
              bank[kTexCarPaintDetailed].mean());
  EXPECT_GT(detailed.second, 2.0 * plain.second);
  EXPECT_GT(detailed.first, 1.5 * plain.first);
  EXPECT_NEAR(bank[kTexCarPaintDetailed].mean(), bank[kTexCarPaint].mean(), 0.15);
}

std::vector<Eigen::Isometry3d> StraightPath(int n, double step, double climb_per_step) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < n; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(0, -climb_per_step * i, step * i);  // y down: climbing = -y
    poses.push_back(T);
  }
  return poses;
}

TEST(SimulatorPath, RoadFollowsTheCameraHeightAndZonesAreLateral) {
  const StreetPath path(StraightPath(101, 1.0, 0.02), 1.65, 2.0, 50.0);
  EXPECT_TRUE(path.down().isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_NEAR(path.PoseArcLength(100), 100.0, 1e-9);
  const PathSample& mid = path.samples()[path.SampleAt(50.0)];
  EXPECT_NEAR(mid.s, 50.0, 1e-9);
  // Camera at (0, -1.0, 50) climbing 2 %: road 1.65 m below it.
  EXPECT_NEAR(mid.road.y(), -1.0 + 1.65, 1e-6);
  EXPECT_NEAR(mid.road.z(), 50.0, 1e-9);
  EXPECT_TRUE(mid.right.isApprox(Eigen::Vector3d::UnitX(), 1e-9));
  // Default profile: road from -5.5 to 2.0 m, sidewalks 2.5 m.
  EXPECT_TRUE(path.InZone(mid.road + Eigen::Vector3d(1.0, 0, 0), Zone::kLane, 0.0));
  EXPECT_FALSE(path.InZone(mid.road + Eigen::Vector3d(1.8, 0, 0), Zone::kLane, 0.0));
  EXPECT_TRUE(path.InZone(mid.road + Eigen::Vector3d(-5.0, 0, 0), Zone::kRoad, 0.0));
  EXPECT_FALSE(path.InZone(mid.road + Eigen::Vector3d(3.0, 0, 0), Zone::kRoad, 0.0));
  EXPECT_TRUE(path.InZone(mid.road + Eigen::Vector3d(3.0, 0, 0), Zone::kStreet, 0.0));
  EXPECT_FALSE(path.InZone(mid.road + Eigen::Vector3d(6.0, 0, 0), Zone::kStreet, 0.0));
  // The street extends straight beyond the last pose.
  EXPECT_NEAR(path.samples().back().s, 150.0, 2.0);
}

TEST(SimulatorPath, DrivingBackAlongTheSameStreetIsMerged) {
  // 100 m forward, a U-turn 3 m to the left, 100 m back.
  std::vector<Eigen::Isometry3d> poses = StraightPath(101, 1.0, 0.0);
  for (int i = 0; i <= 100; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(-3.0, 0, 100.0 - i);
    poses.push_back(T);
  }
  StreetPath path(poses, 1.65, 2.0, 20.0);
  for (auto& s : path.mutable_samples()) s.profile.left_edge = -2.0;  // narrow one-way street
  path.MergeRevisits(kRevisitMergeRadius, kRevisitMinArcGap);
  int merged = 0;
  for (const auto& s : path.samples()) merged += s.merged_into >= 0;
  EXPECT_GT(merged, 35);  // most of the way back
  // The first pass's street now holds the return lane (3 m left, +-2 m).
  const PathSample& first = path.samples()[path.SampleAt(30.0)];
  EXPECT_LE(first.profile.left_edge, -3.0 - 2.0 + 1e-9);
  EXPECT_TRUE(path.InZone(first.road + Eigen::Vector3d(-3.0, 0, 0), Zone::kRoad, 0.0));
}

TEST(SimulatorPath, InventedStreetsBeyondTheEndsYieldToTheDrivenPath) {
  // 100 m along +z from the origin, then around: left to x = -100, back to z = -100, across to x = 0, 1 m
  // lower (y down), and down the street the path adds straight behind its start (x = 0, z < 0) to z = -250:
  // without the fix that last leg is merged into the invented street (laid at the start's height).
  std::vector<Eigen::Isometry3d> poses;
  auto leg = [&](const Eigen::Vector3d& from, const Eigen::Vector3d& to, double y) {
    const Eigen::Vector3d dir = (to - from).normalized();
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear().col(2) = dir;
    T.linear().col(1) = Eigen::Vector3d::UnitY();
    T.linear().col(0) = T.linear().col(1).cross(dir);
    for (double t = 0; t < (to - from).norm(); t += 1.0) {
      T.translation() = from + t * dir + Eigen::Vector3d(0, y, 0);
      poses.push_back(T);
    }
  };
  leg({0, 0, 0}, {0, 0, 100}, 0.0);
  leg({0, 0, 100}, {-100, 0, 100}, 0.0);
  leg({-100, 0, 100}, {-100, 0, -100}, 0.0);
  leg({-100, 0, -100}, {0, 0, -100}, 1.0);
  leg({0, 0, -100}, {0, 0, -250}, 1.0);
  StreetPath path(poses, 1.65, 2.0, 300.0);
  path.DropExtensionsOverThePath(kExtensionYieldRadius, kRevisitMinArcGap);
  path.MergeRevisits(kRevisitMergeRadius, kRevisitMinArcGap);
  const double total = path.PoseArcLength(static_cast<int>(poses.size()) - 1);
  int dropped = 0, onto_extension = 0;
  for (const PathSample& sample : path.samples()) {
    const bool extension = sample.s < 0 || sample.s > total;
    if (extension && sample.merged_into >= 0) {
      ++dropped;
      // Only where the driven path is near: along the last leg (x = 0, z = -88 to -262).
      const PathSample& onto = path.samples()[sample.merged_into];
      EXPECT_LT((sample.road - onto.road).cwiseProduct(Eigen::Vector3d(1, 0, 1)).norm(), 12.0);
    }
    if (!extension && sample.merged_into >= 0) {
      const PathSample& onto = path.samples()[sample.merged_into];
      onto_extension += onto.s < 0 || onto.s > total;
    }
  }
  std::printf("invented samples dropped %d, driven samples merged into invented ones %d\n", dropped, onto_extension);
  EXPECT_GE(dropped, 80);  // ~175 m of the pre-start street under the last legs, every 2 m
  EXPECT_EQ(onto_extension, 0);
  // The pre-start street right behind the start (within 60 m of path) stays.
  EXPECT_LT(path.samples()[path.SampleAt(-10.0)].merged_into, 0);
  EXPECT_GE(path.samples()[path.SampleAt(-100.0)].merged_into, 0);
}

// 100 m forward, a U-turn 3 m to the left, 100 m back `drift` m lower (y down): a revisit whose
// recorded altitude drifted, as KITTI's GPS/IMU poses do.
std::vector<Eigen::Isometry3d> RevisitWithDrift(double drift) {
  std::vector<Eigen::Isometry3d> poses = StraightPath(101, 1.0, 0.0);
  for (int i = 0; i <= 100; ++i) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(-3.0, drift, 100.0 - i);
    poses.push_back(T);
  }
  return poses;
}

TEST(SimulatorPath, AltitudeDriftOfARevisitIsReconciledSmoothly) {
  const double drift = 0.6;
  std::vector<Eigen::Isometry3d> poses = RevisitWithDrift(drift);
  const std::vector<AltitudeCorrection> corrections = AltitudeCorrections(poses, AltitudeReconciliationOptions());
  ASSERT_EQ(corrections.size(), poses.size());
  // Where the passes are paired (>= 60 m of path apart: z < ~70 m), both now lie at one height.
  for (int z = 0; z <= 60; z += 10) {
    const int forward = z, back = 101 + (100 - z);
    const double height_forward = poses[forward].translation().y() + corrections[forward].offset;
    const double height_back = poses[back].translation().y() + corrections[back].offset;
    EXPECT_NEAR(height_forward, height_back, 0.03) << "z " << z;
  }
  // The change is spread along the path: no step between poses (1 m apart, 3 m across the U-turn),
  // a slope of ~1 % at most, and the slope is the offset's derivative along the path.
  for (size_t i = 1; i < poses.size(); ++i) {
    const double arc = i == 101 ? 3.0 : 1.0;
    EXPECT_LT(std::abs(corrections[i].offset - corrections[i - 1].offset) / arc, 0.015) << i;
    EXPECT_LT(std::abs(corrections[i].slope), 0.015) << i;
  }
  for (int i : {30, 90, 110, 170}) {
    const double difference = (corrections[i + 1].offset - corrections[i - 1].offset) / 2.0;
    EXPECT_NEAR(corrections[i].slope, difference, 1e-3) << i;
  }
  // A path that never comes back is left exactly as it is.
  for (const AltitudeCorrection& c : AltitudeCorrections(StraightPath(300, 1.0, 0.02), {})) {
    EXPECT_EQ(c.offset, 0.0);
    EXPECT_EQ(c.slope, 0.0);
  }
  // Passes farther apart vertically than max_difference are different levels (a bridge).
  AltitudeReconciliationOptions bridge;
  bridge.max_difference = 0.5;
  for (const AltitudeCorrection& c : AltitudeCorrections(poses, bridge)) EXPECT_EQ(c.offset, 0.0);
  bridge.min_gap = 10;  // < 2 x radius: neighbours on one pass would count as a revisit
  EXPECT_THROW(AltitudeCorrections(poses, bridge), Error);
}

TEST(SimulatorPath, AppliedCorrectionMovesAndPitchesThePoseByHand) {
  // Camera at the origin looking along +z (KITTI: y down); the correction lowers it by 0.5 m
  // and the road ahead by 10 % more per metre.
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  poses[1].translation() = Eigen::Vector3d(0, 0, 1);
  ApplyAltitudeCorrections({{0.5, 0.1}, {0.0, 0.0}}, &poses);
  EXPECT_TRUE(poses[0].translation().isApprox(Eigen::Vector3d(0, 0.5, 0), 1e-12));
  // Forward turned towards down by atan(0.1): (0, sin, cos); the x axis stays.
  const double angle = std::atan(0.1);
  EXPECT_TRUE(poses[0].linear().col(2).isApprox(Eigen::Vector3d(0, std::sin(angle), std::cos(angle)), 1e-12));
  EXPECT_TRUE(poses[0].linear().col(0).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(poses[1].isApprox(Eigen::Isometry3d(Eigen::Translation3d(0, 0, 1)), 1e-12));
  std::vector<AltitudeCorrection> too_few(1);
  EXPECT_THROW(ApplyAltitudeCorrections(too_few, &poses), Error);
  // Reversing: the camera still looks along +z but travels along -z; the road lowered ahead in the
  // direction of travel tilts the travel direction down, i.e. the camera's view up.
  std::vector<Eigen::Isometry3d> reversing(2, Eigen::Isometry3d::Identity());
  reversing[0].translation() = Eigen::Vector3d(0, 0, 1);
  ApplyAltitudeCorrections({{0.0, 0.1}, {0.0, 0.1}}, &reversing);
  for (const auto& T : reversing)
    EXPECT_TRUE(T.linear().col(2).isApprox(Eigen::Vector3d(0, -std::sin(angle), std::cos(angle)), 1e-12));
}

TEST(SimulatorShadows, BoxShadowIsCastAwayFromTheSun) {
  const Eigen::Vector3d down = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d to_sun = Eigen::Vector3d(1, -1, 0).normalized();  // 45 degrees, towards +x
  ShadowBox box;
  box.center = Eigen::Vector3d(0, -5, 0);  // 10 m tall box standing on y = 0, 2 m wide
  box.axis[0] = Eigen::Vector3d::UnitZ();
  box.axis[1] = Eigen::Vector3d::UnitX();
  box.axis[2] = -down;
  box.half[0] = 1;
  box.half[1] = 1;
  box.half[2] = 5;
  const ShadowCasters casters({box}, {}, down, to_sun);
  // Ground at 5 m on the side away from the sun: the ray to the sun passes through the box.
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(-5, 0, 0), -1), 1.f);
  // Beyond the shadow's tip (10 m tall at 45 degrees: 11 m), on the sunny side, and beside it: lit.
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(-12, 0, 0), -1), 0.f);
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(5, 0, 0), -1), 0.f);
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(-5, 0, 3), -1), 0.f);
  // The surface's own caster is not tested.
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(-5, 0, 0), ShadowCasters::BoxId(0)), 0.f);
  // Penumbra: partial occlusion right at the shadow's edge (z = 1 is the box side).
  const float edge = casters.Occlusion(Eigen::Vector3d(-5, 0, 0.99), -1);
  EXPECT_GT(edge, 0.f);
  EXPECT_LT(edge, 1.f);
}

TEST(SimulatorShadows, TreeCrownShadow) {
  const Eigen::Vector3d down = Eigen::Vector3d::UnitY();
  ShadowEllipsoid crown;
  crown.center = Eigen::Vector3d(0, -5, 0);
  crown.radius_h = 2;
  crown.radius_v = 2;
  const ShadowCasters casters({}, {crown}, down, -down);  // sun at the zenith
  EXPECT_NEAR(casters.Occlusion(Eigen::Vector3d(0, 0, 0), -1), crown.opacity, 1e-6);
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(3, 0, 0), -1), 0.f);
  EXPECT_FLOAT_EQ(casters.Occlusion(Eigen::Vector3d(0, -8, 0), -1), 0.f);  // above the crown
}

}  // namespace
}  // namespace dvso::sim
