// Speed of label extraction (issue 4: "label extraction runs at stereo-odometry
// speed"): the stereo odometry over the same in-memory frames, once alone and
// once with the LabelWriter attached (projection, stereo check, PNG writing),
// plus the stereo check alone on one frame's label candidates. Images are
// loaded before timing, so decoding is not measured.
//
//   bench_labels SEQUENCE_DIR [num_frames=100] [first=0] [config.yaml]
//   (SEQUENCE_DIR: KITTI layout with image_0/ image_1/, e.g. a `dvso simulate` output)
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <unistd.h>

#include <vector>

#include "core/sequence.h"
#include "sdso_labels/label_runner.h"
#include "sdso_labels/label_writer.h"
#include "vo/system/system.h"

namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

struct RunResult {
  double mean_ms = 0;
  double labels_per_frame = 0;
  dvso::labels::LabelCounters counters;
};

// Stereo odometry over the frames; with labels when `label_dir` is not empty.
RunResult Run(const dvso::labels::LabelRunOptions& options, const dvso::StereoCamera& camera,
              const std::vector<dvso::StereoFrame>& frames, int first, const std::string& label_dir,
              bool worker_thread) {
  dvso::vo::System system(options.odometry, camera, dvso::vo::OdometryMode::kStereo);
  std::unique_ptr<dvso::labels::LabelWriter> writer;
  long labels = 0;
  if (!label_dir.empty()) {
    dvso::labels::LabelOptions label_options = options.labels;
    label_options.overwrite = true;
    writer = std::make_unique<dvso::labels::LabelWriter>(
        camera, label_options, label_dir, [&](int, const cv::Mat& map) { labels += cv::countNonZero(map); },
        [&](int index, cv::Mat* left, cv::Mat* right) {
          *left = frames[index - first].left;
          *right = frames[index - first].right;
        },
        worker_thread);
    system.AddObserver(writer.get());
  }
  const auto start = Clock::now();
  for (size_t i = 0; i < frames.size(); ++i) {
    system.ProcessFrame(first + static_cast<int>(i), frames[i].timestamp, frames[i].left, frames[i].right);
  }
  system.Finish();
  RunResult result;
  result.mean_ms = MsSince(start) / frames.size();
  result.labels_per_frame = static_cast<double>(labels) / frames.size();
  if (writer) result.counters = writer->counters();
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s SEQUENCE_DIR [num_frames=100] [first=0] [config.yaml]\n", argv[0]);
    return 2;
  }
  const std::string sequence_dir = argv[1];
  const int count = argc > 2 ? std::stoi(argv[2]) : 100;
  const int first = argc > 3 ? std::stoi(argv[3]) : 0;
  dvso::labels::LabelRunOptions options;
  if (argc > 4) options = dvso::labels::LoadLabelRunOptions(argv[4]);
  const auto sequence = dvso::OpenSequence(sequence_dir);
  const int end = std::min(sequence->size(), first + count);
  std::vector<dvso::StereoFrame> frames;
  for (int i = first; i < end; ++i) frames.push_back(sequence->Read(i));
  const std::string label_dir =
      (std::filesystem::temp_directory_path() / ("bench_labels_" + std::to_string(::getpid()))).string();

  const RunResult alone = Run(options, sequence->camera(), frames, first, "", false);
  const RunResult with = Run(options, sequence->camera(), frames, first, label_dir, false);
  const RunResult beside = Run(options, sequence->camera(), frames, first, label_dir, true);
  const int n = static_cast<int>(frames.size());
  std::printf("%d frames %dx%d of %s\n", n, sequence->camera().left.width, sequence->camera().left.height,
              sequence_dir.c_str());
  std::printf("odometry alone:       %.1f ms/frame\n", alone.mean_ms);
  std::printf("odometry + labels:    %.1f ms/frame (%.0f labels/frame), one thread\n", with.mean_ms,
              with.labels_per_frame);
  std::printf("odometry + labels:    %.1f ms/frame (%.0f labels/frame), labels on a worker thread\n", beside.mean_ms,
              beside.labels_per_frame);
  std::printf("  label writer:       %.1f ms/frame (projection %.1f, stereo check %.1f, PNG %.1f); "
              "stereo check kept %ld of %ld\n",
              (with.counters.extract_ms + with.counters.write_ms) / n,
              (with.counters.extract_ms - with.counters.check_ms) / n, with.counters.check_ms / n,
              with.counters.write_ms / n, with.counters.verified, with.counters.projected);

  // The stereo check alone on the middle frame's candidates (the writer's projected labels
  // are not exposed; a dense grid of candidates at the check's own best match is used).
  const dvso::StereoFrame& mid = frames[n / 2];
  cv::Mat candidates(mid.left.size(), CV_32F, cv::Scalar(0));
  const int per_frame = std::max(1L, with.counters.projected / n);
  const int step = std::max(1, static_cast<int>(std::sqrt(mid.left.total() / static_cast<double>(per_frame))));
  for (int y = step / 2; y < candidates.rows; y += step) {
    for (int x = step / 2; x < candidates.cols; x += step) candidates.at<float>(y, x) = 20.f;
  }
  const int repeats = 10;
  double construct_ms = 0, verify_ms = 0;
  for (int k = 0; k < repeats; ++k) {
    auto start = Clock::now();
    dvso::labels::StereoLabelChecker checker(mid.left, mid.right, options.labels.stereo_check);
    construct_ms += MsSince(start);
    start = Clock::now();
    for (int y = 0; y < candidates.rows; ++y) {
      const float* row = candidates.ptr<float>(y);
      for (int x = 0; x < candidates.cols; ++x) {
        if (row[x] > 0) checker.Keep(x, y, row[x]);
      }
    }
    verify_ms += MsSince(start);
  }
  std::printf("stereo check, frame %d: setup %.2f ms, %d grid candidates (forward scans) %.2f ms\n", first + n / 2,
              construct_ms / repeats, cv::countNonZero(candidates), verify_ms / repeats);
  std::filesystem::remove_all(label_dir);
  return 0;
}
