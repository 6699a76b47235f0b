#include "core/sequence_common.h"

#include <algorithm>
#include <cmath>
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

bool SameRectifiedCamera(const std::vector<double>& p, const std::vector<double>& q) {
  if (p.size() != 12 || q.size() != 12) return false;
  // Entries are pixels (K) and pixel-metres (f t): a thousandth of a pixel / of f x 1 mm is "equal"
  // for numbers printed with 6+ significant digits.
  const double scale = std::max({std::abs(p[0]), std::abs(q[0]), 1.0});
  for (size_t i = 0; i < 12; ++i) {
    if (std::abs(p[i] - q[i]) > 1e-6 * scale + 1e-3) return false;
  }
  return true;
}

bool ColourPairMatchesGrey(const std::vector<double>& grey_left, const std::vector<double>* grey_right,
                           const std::vector<double>& colour_left, const std::vector<double>* colour_right) {
  if (!SameRectifiedCamera(grey_left, colour_left)) return false;
  return colour_right == nullptr || (grey_right != nullptr && SameRectifiedCamera(*grey_right, *colour_right));
}

}  // namespace dvso::internal
