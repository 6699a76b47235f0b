#include "core/sequence_common.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace dvso::internal {

namespace {

cv::Mat LoadRaw(const std::string& path, cv::Size expected) {
  RequireFile(std::filesystem::is_regular_file(path), path, "image file does not exist");
  cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  RequireFile(!raw.empty(), path, "cannot decode image");
  if (raw.depth() == CV_16U) raw.convertTo(raw, CV_8U, 1.0 / 256.0);
  RequireFile(raw.depth() == CV_8U, path, "unsupported pixel depth (expected 8 or 16 bit)");
  if (expected.area() > 0) {
    RequireFile(raw.size() == expected, path,
                "image is " + std::to_string(raw.cols) + "x" + std::to_string(raw.rows) + ", expected " +
                    std::to_string(expected.width) + "x" + std::to_string(expected.height) +
                    " (all frames and the calibration must agree)");
  }
  return raw;
}

}  // namespace

cv::Mat LoadGreyImage(const std::string& path, cv::Size expected) {
  cv::Mat raw = LoadRaw(path, expected);
  if (raw.channels() == 1) return raw;
  cv::Mat grey;
  cv::cvtColor(raw, grey, raw.channels() == 4 ? cv::COLOR_BGRA2GRAY : cv::COLOR_BGR2GRAY);
  return grey;
}

cv::Mat LoadColorImage(const std::string& path, cv::Size expected) {
  cv::Mat raw = LoadRaw(path, expected);
  if (raw.channels() == 3) return raw;
  cv::Mat color;
  cv::cvtColor(raw, color, raw.channels() == 4 ? cv::COLOR_BGRA2BGR : cv::COLOR_GRAY2BGR);
  return color;
}

std::vector<std::string> ListImages(const std::string& directory) {
  namespace fs = std::filesystem;
  RequireFile(fs::is_directory(directory), directory, "image directory does not exist");
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator(directory)) {
    if (!entry.is_regular_file()) continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".bmp") {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace dvso::internal
