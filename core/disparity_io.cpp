#include "core/disparity_io.h"
#include "core/disparity_source.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/image_file.h"

namespace dvso {

cv::Mat ReadKittiMapPng(const std::string& path) {
  RequireFile(std::filesystem::is_regular_file(path), path, "map file does not exist");
  // Unchanged: a grey conversion would accept a 16-bit colour PNG (an image, not a map) as a blend of its channels.
  const cv::Mat raw = cv::imread(path, cv::IMREAD_UNCHANGED);
  RequireFile(!raw.empty(), path, "cannot decode PNG");
  RequireFile(raw.depth() == CV_16U && raw.channels() == 1, path,
              "expected a single-channel uint16 PNG (KITTI map convention), got " + std::to_string(raw.channels()) +
                  " channel(s) of " + (raw.depth() == CV_16U ? "16" : raw.depth() == CV_8U ? "8" : "other") +
                  "-bit values");
  cv::Mat map;
  raw.convertTo(map, CV_32F, 1.0 / 256.0);
  return map;
}

cv::Mat InvalidBeyondKittiMapRange(const cv::Mat& map) {
  Require(map.type() == CV_32FC1, "InvalidBeyondKittiMapRange expects a CV_32FC1 map");
  cv::Mat out = map.clone();
  out.setTo(0.f, out > kKittiMapMaxValue);
  return out;
}

void WriteKittiMapPng(const std::string& path, const cv::Mat& map) {
  Require(map.type() == CV_32FC1, "WriteKittiMapPng expects a CV_32FC1 map (" + path + ")");
  cv::Mat out(map.size(), CV_16UC1);
  for (int y = 0; y < map.rows; ++y) {
    const float* src = map.ptr<float>(y);
    uint16_t* dst = out.ptr<uint16_t>(y);
    for (int x = 0; x < map.cols; ++x) {
      const float v = src[x];
      if (!std::isfinite(v) || v <= 0.f) {
        dst[x] = 0;
      } else {
        // A positive value must never collapse to 0 (= invalid).
        dst[x] = static_cast<uint16_t>(std::min(65535.f, std::max(1.f, std::round(v * 256.f))));
      }
    }
  }
  WriteImageAtomically(path, out);
}

namespace {

// Parses the .npy header; returns the data offset. Supports v1/v2 headers,
// little-endian float32, C order, 3 dimensions.
size_t ParseNpyHeader(const std::string& path, const char* data, size_t size, int* n, int* h, int* w) {
  RequireFile(size >= 10 && std::memcmp(data, "\x93NUMPY", 6) == 0, path, "not a .npy file");
  const int major = static_cast<unsigned char>(data[6]);
  size_t header_len = 0, offset = 0;
  RequireFile(major >= 1 && major <= 3, path, "unknown .npy format version " + std::to_string(major));
  if (major == 1) {
    header_len = static_cast<unsigned char>(data[8]) | (static_cast<unsigned char>(data[9]) << 8);
    offset = 10;
  } else {
    RequireFile(size >= 12, path, "truncated .npy header");
    header_len = 0;
    for (int i = 0; i < 4; ++i) header_len |= static_cast<size_t>(static_cast<unsigned char>(data[8 + i])) << (8 * i);
    offset = 12;
  }
  RequireFile(offset + header_len <= size, path, "truncated .npy header");
  const std::string header(data + offset, header_len);
  RequireFile(header.find("'descr': '<f4'") != std::string::npos, path,
              "expected little-endian float32 data ('<f4')");
  RequireFile(header.find("'fortran_order': False") != std::string::npos, path,
              "Fortran-order arrays are not supported");
  const auto open = header.find("'shape': (");
  RequireFile(open != std::string::npos, path, "no shape in .npy header");
  const auto close = header.find(')', open);
  std::string shape = header.substr(open + 10, close - open - 10);
  std::vector<long> dims;
  size_t pos = 0;
  while (pos < shape.size()) {
    while (pos < shape.size() && (shape[pos] == ' ' || shape[pos] == ',')) ++pos;
    if (pos >= shape.size()) break;
    // Digits, then an optional 'L' (Python 2 wrote long dimensions as "3L").
    size_t end = pos;
    while (end < shape.size() && std::isdigit(static_cast<unsigned char>(shape[end]))) ++end;
    RequireFile(end > pos, path, "unreadable shape '(" + shape + ")' in the .npy header");
    dims.push_back(std::stol(shape.substr(pos, end - pos)));
    pos = end;
    if (pos < shape.size() && shape[pos] == 'L') ++pos;
  }
  RequireFile(dims.size() == 3, path, "expected a (N, H, W) array, got " + std::to_string(dims.size()) + " dims");
  constexpr long kMaxDimension = 1 << 20;
  for (long d : dims) {
    RequireFile(d > 0 && d < kMaxDimension, path, "shape '(" + shape + ")' has an empty or implausible dimension");
  }
  *n = static_cast<int>(dims[0]);
  *h = static_cast<int>(dims[1]);
  *w = static_cast<int>(dims[2]);
  const size_t data_offset = offset + header_len;
  RequireFile(data_offset + sizeof(float) * static_cast<size_t>(*n) * *h * *w <= size, path,
              "file shorter than its shape says");
  return data_offset;
}

}  // namespace

NpyDisparityStack::NpyDisparityStack(const std::string& path) : path_(path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  RequireFile(fd >= 0, path, "cannot open .npy file");
  struct stat st {};
  if (::fstat(fd, &st) != 0 || st.st_size <= 0) {
    ::close(fd);
    throw Error(path, "cannot stat .npy file or file is empty");
  }
  mapped_size_ = static_cast<size_t>(st.st_size);
  mapped_ = ::mmap(nullptr, mapped_size_, PROT_READ, MAP_PRIVATE, fd, 0);
  ::close(fd);
  RequireFile(mapped_ != MAP_FAILED, path, "cannot memory-map .npy file");
  try {
    data_offset_ = ParseNpyHeader(path, static_cast<const char*>(mapped_), mapped_size_, &count_, &height_, &width_);
  } catch (...) {
    ::munmap(mapped_, mapped_size_);
    mapped_ = nullptr;
    throw;
  }
}

NpyDisparityStack::~NpyDisparityStack() {
  if (mapped_ != nullptr && mapped_ != MAP_FAILED) ::munmap(mapped_, mapped_size_);
}

cv::Mat NpyDisparityStack::Frame(int index, int image_width, int image_height, NonFiniteDisparity non_finite) const {
  RequireFile(index >= 0 && index < count_, path_,
              "frame " + std::to_string(index) + " out of range (stack holds " + std::to_string(count_) + ")");
  const float* base = reinterpret_cast<const float*>(static_cast<const char*>(mapped_) + data_offset_) +
                      static_cast<size_t>(index) * height_ * width_;
  // Non-finite values (a network's NaN) become 0 = invalid: no depth there, unless the caller refuses them.
  cv::Mat view(height_, width_, CV_32F);
  const float* src = base;
  for (int y = 0; y < height_; ++y) {
    float* row = view.ptr<float>(y);
    for (int x = 0; x < width_; ++x, ++src) {
      if (!std::isfinite(*src) && non_finite == NonFiniteDisparity::kError) {
        throw Error(path_, "frame " + std::to_string(index) + ", pixel (x " + std::to_string(x) + ", y " +
                               std::to_string(y) + "): non-finite value " + std::to_string(*src) +
                               " (predictions must be finite)");
      }
      row[x] = std::isfinite(*src) ? *src : 0.0f;
    }
  }
  // In pixels of the stack's own width, then resized (bilinear, values scaled with the width).
  view *= static_cast<double>(width_);
  return ResizeDisparity(view, image_width, image_height, DisparityResize::kBilinear);
}

void WriteNpyStack(const std::string& path, const std::vector<cv::Mat>& maps) {
  Require(!maps.empty(), "WriteNpyStack: no maps to write (" + path + ")");
  const int h = maps[0].rows, w = maps[0].cols;
  for (const auto& m : maps) {
    Require(m.type() == CV_32FC1 && m.rows == h && m.cols == w, "WriteNpyStack: maps must be CV_32FC1 of equal size");
  }
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (" + std::to_string(maps.size()) + ", " +
                       std::to_string(h) + ", " + std::to_string(w) + "), }";
  const size_t total = 10 + header.size() + 1;
  header.append((64 - total % 64) % 64, ' ');
  header.push_back('\n');
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out.write("\x93NUMPY\x01\x00", 8);
    const uint16_t len = static_cast<uint16_t>(header.size());
    const char len_bytes[2] = {static_cast<char>(len & 0xff), static_cast<char>(len >> 8)};
    out.write(len_bytes, 2);
    out.write(header.data(), static_cast<std::streamsize>(header.size()));
    for (const auto& m : maps) {
      for (int y = 0; y < h; ++y) out.write(reinterpret_cast<const char*>(m.ptr<float>(y)), sizeof(float) * w);
    }
  }, /*binary=*/true);
}

}  // namespace dvso
