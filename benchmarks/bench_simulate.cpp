// Speed of `dvso simulate` at KITTI resolution (1241x376, both views, depth,
// both disparities). Target: >= 5 frames/s with 2 threads on a 2-core machine.
//
//   bench_simulate [trajectory = data/kitti_poses/00.txt, run from the repo root] [frames] [threads] [output_dir]
//
// Prints frames/s for (a) rendering only and (b) rendering + writing all PNGs,
// as wall-clock rates and, because the build machines are shared, also as the
// rate the process CPU time would allow on `threads` otherwise idle cores.
#include <time.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/simulator.h"

namespace {

double CpuSeconds() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}
double WallSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  dvso::SimulatorOptions options;
  options.trajectory_path = argc > 1 ? argv[1] : std::string("data/kitti_poses/00.txt");
  options.num_frames = argc > 2 ? std::stoi(argv[2]) : 30;
  options.num_threads = argc > 3 ? std::stoi(argv[3]) : 2;
  const std::string output_dir = argc > 4 ? argv[4] : "/tmp/dvso_bench_simulate";
  options.first_frame = 100;  // a street with parked cars and trees, not the start of the path

  double wall = WallSeconds(), cpu = CpuSeconds();
  dvso::StreetSimulator simulator(options);
  std::printf("world setup: %.2f s wall, %.2f s cpu (%zu triangles)\n", WallSeconds() - wall, CpuSeconds() - cpu,
              simulator.scene().triangles.size());

  wall = WallSeconds();
  cpu = CpuSeconds();
  double checksum = 0;
  for (int i = 0; i < simulator.num_frames(); ++i) {
    const dvso::SimulatedFrame frame = simulator.Render(i);
    checksum += frame.left.grey.at<uint8_t>(frame.left.grey.rows / 2, frame.left.grey.cols / 2);
  }
  const double render_wall = WallSeconds() - wall, render_cpu = CpuSeconds() - cpu;
  const int n = simulator.num_frames();
  std::printf("render only   (%d frames %dx%d, %d threads): %.2f frames/s wall, %.2f frames/s from cpu time "
              "(checksum %.0f)\n",
              n, options.camera.left.width, options.camera.left.height, options.num_threads, n / render_wall,
              n * options.num_threads / render_cpu, checksum);

  std::filesystem::remove_all(output_dir);
  wall = WallSeconds();
  cpu = CpuSeconds();
  const dvso::SimulationSummary summary = dvso::WriteSimulatedSequence(options, output_dir, false);
  const double all_wall = WallSeconds() - wall, all_cpu = CpuSeconds() - cpu;
  std::printf("render + write (incl. world setup): %.2f frames/s wall, %.2f frames/s from cpu time\n",
              summary.frames / all_wall, summary.frames * options.num_threads / all_cpu);
  std::filesystem::remove_all(output_dir);
  return 0;
}
