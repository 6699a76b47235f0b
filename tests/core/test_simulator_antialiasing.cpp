// The renderer's edge anti-aliasing (core/simulator_render.cpp): a sub-sample that none of the surfaces
// seen at the 3x3 pixel centres around it covers (a ground strip thinner than a pixel far away, a kerb
// face) was shaded as sky until simulator world version 3, a bright fringe below the horizon at far kerbs
// and object feet that the other camera sees elsewhere. From version 4 it is left out.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "core/simulator.h"

namespace dvso {
namespace {

SimulatedFrame RenderVersion(int world_version) {
  SimulatorOptions o;
  o.trajectory_path = std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/08.txt";  // a label world (seed 9680)
  o.first_frame = 3800;
  o.num_frames = 1;
  o.seed = 9680;
  o.vary_appearance = true;
  o.camera = StereoCamera{}.Resized(620, 188);
  o.texture_size = 128;
  o.noise = false;
  o.world_version = world_version;
  return StreetSimulator(o).Render(0);
}

TEST(Simulator, EdgeAntialiasingPutsNoSkyBelowTheHorizonFromWorldVersion4) {
  const SimulatedFrame before = RenderVersion(3), after = RenderVersion(4);
  ASSERT_EQ(cv::norm(before.left.depth, after.left.depth, cv::NORM_INF), 0);  // the same world and GT
  const cv::Mat& depth = after.left.depth;
  int changed_beside_sky = 0, changed = 0, brighter_before = 0;
  for (int y = 1; y + 1 < depth.rows; ++y)
    for (int x = 1; x + 1 < depth.cols; ++x) {
      const int a = before.left.grey.at<uint8_t>(y, x), b = after.left.grey.at<uint8_t>(y, x);
      if (a == b) continue;
      bool sky_beside = false;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) sky_beside |= depth.at<float>(y + dy, x + dx) <= 0;
      if (sky_beside) {
        ++changed_beside_sky;
        continue;
      }
      ++changed;
      brighter_before += a > b + 10;
    }
  std::printf("pixels changed: %d with no sky around (%d of them > 10 grey levels brighter in version 3), %d beside sky\n",
              changed, brighter_before, changed_beside_sky);
  // Silhouettes against the sky keep their sky samples: identical there.
  EXPECT_EQ(changed_beside_sky, 0);
  // Version 3's fringe, gone: pixels with no sky around them that were brighter, by sky's share of the samples.
  EXPECT_GE(changed, 50);
  EXPECT_GE(brighter_before, changed * 9 / 10);
}

}  // namespace
}  // namespace dvso
