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
  std::sort(files.begin(), files.end(), NaturalLess);
  return files;
}

bool NaturalLess(const std::string& a, const std::string& b) {
  const auto is_digit = [](char c) { return c >= '0' && c <= '9'; };
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (is_digit(a[i]) && is_digit(b[j])) {
      size_t i_end = i, j_end = j;
      while (i_end < a.size() && is_digit(a[i_end])) ++i_end;
      while (j_end < b.size() && is_digit(b[j_end])) ++j_end;
      size_t i_start = i, j_start = j;  // the number without leading zeros
      while (i_start + 1 < i_end && a[i_start] == '0') ++i_start;
      while (j_start + 1 < j_end && b[j_start] == '0') ++j_start;
      const size_t i_len = i_end - i_start, j_len = j_end - j_start;
      if (i_len != j_len) return i_len < j_len;
      const int order = a.compare(i_start, i_len, b, j_start, j_len);
      if (order != 0) return order < 0;
      if (i_end - i != j_end - j) return i_end - i < j_end - j;  // 7 before 007: a total order
      i = i_end, j = j_end;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

cv::Size FirstDecodableImageSize(const std::vector<std::string>& files) {
  RequireFile(!files.empty(), "", "no images");
  const size_t probes = std::min(files.size(), static_cast<size_t>(kSizeProbeFrames));
  for (size_t i = 0; i < probes; ++i) {
    const cv::Mat image = cv::imread(files[i], cv::IMREAD_UNCHANGED);
    if (!image.empty()) return image.size();
  }
  throw Error(files[0], "cannot decode image (nor any of the " + std::to_string(probes) + " first frames)");
}

void RequireImagesOfCalibratedSize(const std::vector<std::string>& files, cv::Size calibrated,
                                   const std::string& calibration) {
  const cv::Size size = FirstDecodableImageSize(files);
  RequireFile(size == calibrated, calibration,
              "gives images of " + std::to_string(calibrated.width) + "x" + std::to_string(calibrated.height) +
                  ", but " + std::filesystem::path(files[0]).parent_path().string() + " holds " +
                  std::to_string(size.width) + "x" + std::to_string(size.height) + " images");
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
