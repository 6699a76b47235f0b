// Speed of the odometry at KITTI resolution (1241x376) with default settings.
// Frames come either from a stored KITTI-layout sequence (e.g. the output of
// `dvso simulate`) or from the StreetSimulator along a KITTI trajectory,
// rendered in memory; in both cases all frames are in memory before timing
// (image decoding is not timed). Prints, for mono and stereo, mean / median /
// max wall ms per frame, mean CPU ms per frame (all threads of the process:
// robust to other load on a shared machine, and an upper bound of the wall
// time on an idle machine with enough cores), keyframes, and resident memory
// at the middle and end of each run (memory must stay flat).
//
//   bench_odometry SEQUENCE_DIR [num_frames=all] [mono|stereo|both=both]
//   bench_odometry [num_frames=100] [first_pose=0] [trajectory=data/kitti_poses/00.txt, run from the repo root]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

#include "core/sequence.h"
#include "core/simulator.h"
#include "vo/system/output_writers.h"
#include "vo/system/system.h"

namespace {

double CpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

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
  const double cpu_start = CpuSeconds();
  for (size_t i = 0; i < left.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    system.ProcessFrame(static_cast<int>(i), 0.1 * i, left[i],
                        mode == dvso::vo::OdometryMode::kStereo ? right[i] : cv::Mat());
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    if (i == left.size() / 2) rss_mid = ResidentMiB();
  }
  const double cpu_ms_per_frame = 1000.0 * (CpuSeconds() - cpu_start) / std::max<size_t>(1, left.size());
  system.Finish();
  double sum = 0;
  for (double v : ms) sum += v;
  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  std::printf("%-6s: %zu frames %dx%d, mean %.1f ms/frame wall (median %.1f, max %.1f), %.1f ms/frame CPU, "
              "keyframes %d, lost %d, re-initialisations %d, RSS mid %.0f MiB end %.0f MiB\n",
              dvso::vo::ToString(mode).c_str(), ms.size(), camera.left.width, camera.left.height,
              sum / ms.size(), sorted[sorted.size() / 2], sorted.back(), cpu_ms_per_frame,
              system.num_keyframes_total(), recorder.CountStatus(FrameStatus::kLost), system.num_resets(), rss_mid,
              ResidentMiB());
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<cv::Mat> left, right;
  dvso::StereoCamera camera;
  std::string which = "both";
  if (argc > 1 && std::filesystem::is_directory(argv[1])) {
    const std::unique_ptr<dvso::SequenceReader> sequence = dvso::OpenSequence(argv[1]);
    const int count = argc > 2 ? std::min(std::stoi(argv[2]), sequence->size()) : sequence->size();
    if (argc > 3) which = argv[3];
    camera = sequence->camera();
    std::fprintf(stderr, "loading %d frames of %s ...\n", count, argv[1]);
    for (int i = 0; i < count; ++i) {
      const dvso::StereoFrame f = sequence->Read(i);
      left.push_back(f.left);
      right.push_back(f.right);
    }
  } else {
    const int frames = argc > 1 ? std::stoi(argv[1]) : 100;
    const int first = argc > 2 ? std::stoi(argv[2]) : 0;
    const std::string trajectory = argc > 3 ? argv[3] : std::string("data/kitti_poses/00.txt");
    dvso::SimulatorOptions sim_options;
    sim_options.trajectory_path = trajectory;
    sim_options.first_frame = first;
    sim_options.num_frames = frames;
    sim_options.num_threads = 2;
    const dvso::StreetSimulator simulator(sim_options);
    camera = simulator.camera();
    std::fprintf(stderr, "rendering %d frames of %s ...\n", simulator.num_frames(), trajectory.c_str());
    for (int i = 0; i < simulator.num_frames(); ++i) {
      const dvso::SimulatedFrame f = simulator.Render(i);
      left.push_back(f.left.grey);
      right.push_back(f.right.grey);
    }
  }
  if (which == "both" || which == "mono") RunMode(dvso::vo::OdometryMode::kMono, camera, left, right);
  if (which == "both" || which == "stereo") RunMode(dvso::vo::OdometryMode::kStereo, camera, left, right);
  return 0;
}
