// A short `dvso simulate` sequence rendered in memory at a small size (CI
// stays short), shared by the end-to-end System tests: images, exact
// disparities (for DVSO oracle runs) and the true trajectory.
#pragma once

#include <deque>
#include <string>
#include <vector>

#include "core/simulator.h"

namespace dvso::vo::testing {

struct SimulatedSequence {
  StereoCamera camera;
  std::vector<cv::Mat> left, right;
  std::vector<cv::Mat> disparity_left, disparity_right;  // CV_32F, exact (0 = sky)
  std::vector<Eigen::Isometry3d> truth;  // camera-to-world, first = identity
  double path_length = 0;
};

// The simulator world version of this sequence, fixed so that a simulator change does not move the System tests'
// fixture under them. Version 4 (session 40) changed the edge pixels' anti-aliasing, and two tests' thresholds then
// failed: SystemSimulated.StereoTracksEveryFrameWithMetricScale (oldest keyframe 39 frames back for < 36; 34 in
// version 3: DSO's distance score keeps the first keyframe in both) and ...RightVignetteFileCorrectsTheRightLensAlone
// (one early keyframe's corrected transfer 1.78 % off at 200 for a 1.5 % + 0.5 band). Both margins were one world's.
constexpr int kVoTestWorldVersion = 3;

// `frames` frames from the start of KITTI 00's poses at 416x128 (cached per frame count).
inline const SimulatedSequence& SimulatedKitti00(int frames) {
  static std::deque<std::pair<int, SimulatedSequence>> cache;  // deque: references stay valid
  for (const auto& [n, seq] : cache) {
    if (n == frames) return seq;
  }
  SimulatorOptions o;
  o.trajectory_path = std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/00.txt";
  o.first_frame = 0;
  o.num_frames = frames;
  o.camera = StereoCamera{}.Resized(416, 128);
  o.texture_size = 256;
  o.num_threads = 2;
  o.world_version = kVoTestWorldVersion;
  StreetSimulator sim(o);
  SimulatedSequence s;
  s.camera = sim.camera();
  for (int i = 0; i < sim.num_frames(); ++i) {
    const SimulatedFrame f = sim.Render(i);
    s.left.push_back(f.left.grey);
    s.right.push_back(f.right.grey);
    s.disparity_left.push_back(f.disparity_left);
    s.disparity_right.push_back(f.disparity_right);
    s.truth.push_back(f.T_first_camera);
    if (i > 0) s.path_length += (s.truth[i].translation() - s.truth[i - 1].translation()).norm();
  }
  cache.emplace_back(frames, std::move(s));
  return cache.back().second;
}

}  // namespace dvso::vo::testing
