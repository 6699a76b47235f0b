// Headless timing driver for the original DSO (Engel et al.), used only by
// benchmarks/dso_compare/compare_dso.sh for a side-by-side speed comparison
// with `dvso odometry --mode mono`. It is compiled against a DSO checkout the
// user provides (DSO's code is never part of this repository) and replaces
// DSO's own example main, which needs Pangolin (not packaged in Debian).
//
// Usage: dso_timing_driver IMAGE_DIR CAMERA_FILE OUT_TUM_FILE [MAX_FRAMES]
// Prints one summary line: frames, mean/median ms per frame of
// FullSystem::addActiveFrame (image loading excluded, as in dvso's run log).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "FullSystem/FullSystem.h"
#include "util/DatasetReader.h"
#include "util/globalCalib.h"
#include "util/settings.h"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s IMAGE_DIR CAMERA_FILE OUT_TUM_FILE [MAX_FRAMES]\n", argv[0]);
    return 2;
  }
  const std::string image_dir = argv[1];
  const std::string camera_file = argv[2];
  const std::string out_file = argv[3];
  const int max_frames = argc > 4 ? std::atoi(argv[4]) : -1;

  // DSO's "mode=1" (no photometric calibration file) with its default
  // preset 0: 2000 points, 7 keyframes, no real-time enforcement
  // (linearizeOperation = true: every frame is fully processed, as dvso does).
  dso::setting_photometricCalibration = 0;
  dso::setting_affineOptModeA = 0;
  dso::setting_affineOptModeB = 0;
  dso::disableAllDisplay = true;
  dso::setting_logStuff = false;
  dso::setting_debugout_runquiet = true;
  dso::disableReconfigure = true;

  ImageFolderReader reader(image_dir, camera_file, "", "");
  reader.setGlobalCalibration();
  auto system = std::make_unique<dso::FullSystem>();
  system->setGammaFunction(reader.getPhotometricGamma());
  system->linearizeOperation = true;

  const int frames = max_frames > 0 ? std::min(max_frames, reader.getNumImages()) : reader.getNumImages();
  std::vector<double> ms;
  ms.reserve(frames);
  int resets = 0;
  for (int i = 0; i < frames; ++i) {
    std::unique_ptr<dso::ImageAndExposure> image(reader.getImage(i));
    const auto start = std::chrono::steady_clock::now();
    system->addActiveFrame(image.get(), i);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
    if (system->initFailed || dso::setting_fullResetRequested) {
      // Same policy as DSO's example: restart the system and keep going.
      std::vector<dso::IOWrap::Output3DWrapper*> wrappers = system->outputWrapper;
      system = std::make_unique<dso::FullSystem>();
      system->setGammaFunction(reader.getPhotometricGamma());
      system->linearizeOperation = true;
      system->outputWrapper = wrappers;
      dso::setting_fullResetRequested = false;
      ++resets;
    }
    if (system->isLost) {
      std::fprintf(stderr, "DSO lost tracking at frame %d\n", i);
      break;
    }
  }
  system->blockUntilMappingIsFinished();
  system->printResult(out_file);

  std::vector<double> sorted = ms;
  std::sort(sorted.begin(), sorted.end());
  double sum = 0;
  for (double v : ms) sum += v;
  std::printf("dso frames=%zu resets=%d mean_ms=%.2f median_ms=%.2f\n", ms.size(), resets,
              ms.empty() ? 0.0 : sum / ms.size(), sorted.empty() ? 0.0 : sorted[sorted.size() / 2]);
  return 0;
}
