// Speed of the odometry at KITTI resolution (1241x376) with default settings on
// a simulated sequence (StreetSimulator along KITTI 00, rendered in memory
// before timing). Prints mean / median / max ms per frame for mono and stereo,
// keyframe counts and resident memory at the middle and end of each run
// (memory must stay flat).
//
//   bench_odometry [num_frames=100] [first_pose=0] [trajectory=data/kitti_poses/00.txt, run from the repo root]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "core/simulator.h"
#include "vo/system/output_writers.h"
#include "vo/system/system.h"

namespace {

double ResidentMiB() {
  std::ifstream status("/proc/self/status");
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  }
  return 0;
}

void RunMode(dvso::vo::OdometryMode mode, const dvso::StereoCamera& camera, const std::vector<cv::Mat>& left,
             const std::vector<cv::Mat>& right) {
  using dvso::vo::FrameStatus;
  dvso::vo::System system(dvso::vo::OdometryOptions::Preset("default"), camera, mode);
  dvso::vo::TrajectoryRecorder recorder;
  system.AddObserver(&recorder);
  std::vector<double> ms;
  double rss_mid = 0;
  for (size_t i = 0; i < left.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    system.ProcessFrame(static_cast<int>(i), 0.1 * i, left[i],
                        mode == dvso::vo::OdometryMode::kStereo ? right[i] : cv::Mat());
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    if (i == left.size() / 2) rss_mid = ResidentMiB();
  }
  system.Finish();
  double sum = 0;
  for (double v : ms) sum += v;
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  std::printf("%-6s: %zu frames %dx%d, mean %.1f ms/frame, median %.1f, max %.1f, keyframes %d, lost %d, "
              "RSS mid %.0f MiB end %.0f MiB\n",
              dvso::vo::ToString(mode).c_str(), ms.size(), camera.left.width, camera.left.height,
              sum / ms.size(), sorted[sorted.size() / 2], sorted.back(), system.num_keyframes_total(),
              recorder.CountStatus(FrameStatus::kLost), rss_mid, ResidentMiB());
}

}  // namespace

int main(int argc, char** argv) {
  const int frames = argc > 1 ? std::stoi(argv[1]) : 100;
  const int first = argc > 2 ? std::stoi(argv[2]) : 0;
  const std::string trajectory = argc > 3 ? argv[3] : std::string("data/kitti_poses/00.txt");
  dvso::SimulatorOptions sim_options;
  sim_options.trajectory_path = trajectory;
  sim_options.first_frame = first;
  sim_options.num_frames = frames;
  sim_options.num_threads = 2;
  const dvso::StreetSimulator simulator(sim_options);
  std::vector<cv::Mat> left, right;
  std::fprintf(stderr, "rendering %d frames of %s ...\n", simulator.num_frames(), trajectory.c_str());
  for (int i = 0; i < simulator.num_frames(); ++i) {
    const dvso::SimulatedFrame f = simulator.Render(i);
    left.push_back(f.left.grey);
    right.push_back(f.right.grey);
  }
  RunMode(dvso::vo::OdometryMode::kMono, simulator.camera(), left, right);
  RunMode(dvso::vo::OdometryMode::kStereo, simulator.camera(), left, right);
  return 0;
}
