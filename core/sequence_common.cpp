#include "core/sequence_common.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/fs_util.h"

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
    // A writer killed between writing and renaming leaves 000123.tmp-writing.png (core/fs_util.h): never a frame.
    if (!entry.is_regular_file() || IsUnfinishedAtomicWrite(entry.path())) continue;
    // Hidden files are never frames: macOS writes ._000000.png beside 000000.png on foreign disks.
    if (entry.path().filename().string().front() == '.') continue;
    std::string ext = entry.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".bmp") {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end(), NaturalLess);
  return files;
}

namespace {

bool IsDigit(char c) { return c >= '0' && c <= '9'; }

// The number that starts at `pos`: its integer digits without leading zeros, and the digits after a
// decimal point when one follows (timestamps as names: 1317042130.25.png). `end` is one past it.
struct NameNumber {
  std::string integer, fraction;
  size_t end = 0;
  size_t digits = 0;  // every digit character it spans (leading zeros too)
};

NameNumber ReadNameNumber(const std::string& s, size_t pos) {
  NameNumber n;
  size_t i = pos;
  while (i < s.size() && IsDigit(s[i])) ++i;
  size_t start = pos;
  while (start + 1 < i && s[start] == '0') ++start;
  n.integer = s.substr(start, i - start);
  n.digits = i - pos;
  if (i + 1 < s.size() && s[i] == '.' && IsDigit(s[i + 1])) {
    size_t f = i + 1;
    while (f < s.size() && IsDigit(s[f])) ++f;
    n.fraction = s.substr(i + 1, f - i - 1);
    n.digits += f - i - 1;
    i = f;
  }
  n.end = i;
  return n;
}

// -1, 0, 1 by value: integers by length then digits, fractions digit by digit (".25" < ".3").
int CompareNameNumbers(const NameNumber& a, const NameNumber& b) {
  if (a.integer.size() != b.integer.size()) return a.integer.size() < b.integer.size() ? -1 : 1;
  if (const int c = a.integer.compare(b.integer); c != 0) return c < 0 ? -1 : 1;
  const size_t n = std::max(a.fraction.size(), b.fraction.size());
  for (size_t k = 0; k < n; ++k) {
    const char x = k < a.fraction.size() ? a.fraction[k] : '0';
    const char y = k < b.fraction.size() ? b.fraction[k] : '0';
    if (x != y) return x < y ? -1 : 1;
  }
  return 0;
}

}  // namespace

bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (IsDigit(a[i]) && IsDigit(b[j])) {
      const NameNumber x = ReadNameNumber(a, i), y = ReadNameNumber(b, j);
      if (const int c = CompareNameNumbers(x, y); c != 0) return c < 0;
      if (x.digits != y.digits) return x.digits < y.digits;  // 7 before 007, 1.5 before 1.50
      i = x.end, j = y.end;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i, ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;  // names equal as numbers (01 and 1.0): text order, so that the order is total
}

std::string FirstMissingNumberedFrame(const std::vector<std::string>& files, size_t count) {
  namespace fs = std::filesystem;
  if (files.empty()) return "";
  const fs::path first(files.front());
  const std::string extension = first.extension().string();
  const size_t width = first.stem().string().size();
  std::vector<long long> numbers;
  for (const std::string& file : files) {
    const fs::path path(file);
    const std::string stem = path.stem().string();
    if (stem.empty() || stem.size() != width || stem.size() > 12 || path.extension() != extension ||
        path.parent_path() != first.parent_path() || stem.find_first_not_of("0123456789") != std::string::npos) {
      return "";
    }
    numbers.push_back(std::stoll(stem));
  }
  std::sort(numbers.begin(), numbers.end());
  // A clip cut out of a longer recording, with a times.txt of its own length: frame i is its i-th image.
  const long long start = count > 0 && count == numbers.size() ? numbers.front() : 0;
  const long long end = std::max(numbers.back() + 1, start + static_cast<long long>(count));
  long long expected = start;
  for (const long long n : numbers) {
    if (n != expected) break;
    ++expected;
  }
  if (expected >= end) return "";
  std::string stem = std::to_string(expected);
  stem.insert(0, width > stem.size() ? width - stem.size() : 0, '0');
  return (first.parent_path() / (stem + extension)).string();
}

cv::Size FirstDecodableImageSize(const std::vector<std::string>& files) {
  RequireFile(!files.empty(), "", "no images");
  const size_t probes = std::min(files.size(), static_cast<size_t>(kSizeProbeFrames));
  for (size_t i = 0; i < probes; ++i) {
    const cv::Mat image = cv::imread(files[i], cv::IMREAD_UNCHANGED);
    if (image.empty()) continue;
    if (image.depth() == CV_16U) RequireSixteenBitRange(files, i, probes);
    return image.size();
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

cv::Vec3d RectifiedCameraOffset(const std::vector<double>& projection, const std::string& calibration) {
  RequireFile(projection.size() == 12, calibration, "a projection matrix has 12 numbers");
  const std::vector<double>& p = projection;
  const cv::Matx33d K(p[0], p[1], p[2], p[4], p[5], p[6], p[8], p[9], p[10]);
  RequireFile(cv::determinant(K) != 0.0, calibration, "a projection matrix's left 3x3 block (K) is singular");
  return K.solve(cv::Vec3d(p[3], p[7], p[11]), cv::DECOMP_LU);
}

double RectifiedBaseline(const std::vector<double>& p_left, const std::vector<double>& p_right,
                         const std::string& calibration) {
  return RectifiedCameraOffset(p_left, calibration)[0] - RectifiedCameraOffset(p_right, calibration)[0];
}

void CheckPrincipalPointFitsImages(double cx, double cy, int width, int height, const std::string& calibration) {
  const std::string images = std::to_string(width) + "x" + std::to_string(height) + " images";
  std::ostringstream point;
  point << "principal point (" << cx << ", " << cy << ")";
  RequireFile(cx >= 0 && cx <= width && cy >= 0 && cy <= height, calibration,
              point.str() + " lies outside the " + images +
                  ": a calibration for another image size? (scale fx, fy, cx, cy and P[0][3] with the images)");
  const double off_centre = std::max(std::abs(cx / width - 0.5), std::abs(cy / height - 0.5));
  if (off_centre > kPrincipalPointWarnOffset) {
    std::cerr << "dvso: warning: " << calibration << ": " << point.str() << " lies far from the centre of the "
              << images << ": is the calibration for another image size? (its intrinsics must be scaled with the "
              << "images)" << std::endl;
  }
}

void RequireSixteenBitRange(const std::vector<std::string>& files, size_t first, size_t end) {
  double max_value = 0;
  for (size_t i = first; i < end && max_value < kMinSixteenBitMaximum; ++i) {
    const cv::Mat image = cv::imread(files[i], cv::IMREAD_UNCHANGED);
    if (image.empty() || image.depth() != CV_16U) continue;
    std::vector<cv::Mat> channels;
    cv::split(image, channels);
    if (channels.size() == 4) channels.pop_back();  // alpha says nothing about the sensor's range
    for (const cv::Mat& channel : channels) {
      double channel_max = 0;
      cv::minMaxLoc(channel, nullptr, &channel_max);
      max_value = std::max(max_value, channel_max);
    }
  }
  RequireFile(max_value >= kMinSixteenBitMaximum, files[first],
              "16-bit image whose values stop at " + std::to_string(static_cast<int>(max_value)) +
                  " of 65535 (a 12-bit sensor's, or 8-bit values; so do the next frames): read as full-range 16 bit "
                  "it would be nearly black; scale the images to 8 bit or to the full 16-bit range");
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
