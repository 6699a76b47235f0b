// Disparity and depth maps on disk: KITTI uint16 PNG (value * 256, 0 = invalid)
// and monodepth-style .npy stacks (float32 N x H x W, disparity / image width).
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

namespace dvso {

// Reads a KITTI uint16 PNG into CV_32F; invalid pixels (0) become 0. Throws
// dvso::Error naming the file if it is missing, unreadable, not 16-bit or has more than one channel.
cv::Mat ReadKittiMapPng(const std::string& path);

// Writes a CV_32F map as KITTI uint16 PNG (round(value * 256), clamped to
// 1..65535 for positive values; <= 0 or non-finite = 0 = invalid). Atomic.
void WriteKittiMapPng(const std::string& path, const cv::Mat& map);

// Largest value a KITTI uint16 PNG holds (65535 / 256 = 255.996 px or m).
inline constexpr float kKittiMapMaxValue = 65535.0f / 256.0f;

// Copy of a CV_32F ground-truth map with values the PNG cannot hold set to 0
// (invalid): WriteKittiMapPng would clamp them, and a clamped GT value is a
// wrong one (a 2.7 m near depth at 2x KITTI size has ~285 px of disparity).
cv::Mat InvalidBeyondKittiMapRange(const cv::Mat& map);

// What NpyDisparityStack::Frame makes of a non-finite value (a network's NaN or inf): 0 = invalid, "no
// depth here" (the odometry's disparity sources, which skip such pixels), or an error (evaluation, where a
// 0 would be scored as the farthest depth instead of showing that the prediction is broken).
enum class NonFiniteDisparity { kInvalid, kError };

// Memory-mapped float32 .npy stack of shape (N, H, W) holding disparities
// normalised by image width (monodepth / unofficial DVSO convention).
class NpyDisparityStack {
 public:
  explicit NpyDisparityStack(const std::string& path);
  ~NpyDisparityStack();
  NpyDisparityStack(const NpyDisparityStack&) = delete;
  NpyDisparityStack& operator=(const NpyDisparityStack&) = delete;

  int size() const { return count_; }
  int height() const { return height_; }
  int width() const { return width_; }
  // Frame i as CV_32F in pixels of an image `image_width` wide (value * image_width),
  // resized to image_width x image_height when those differ from the stack's size.
  // Non-finite values become 0 (invalid), or with kError throw dvso::Error naming the file, frame and
  // pixel. Throws dvso::Error on an out-of-range index.
  cv::Mat Frame(int index, int image_width, int image_height,
                NonFiniteDisparity non_finite = NonFiniteDisparity::kInvalid) const;

 private:
  std::string path_;
  int count_ = 0, height_ = 0, width_ = 0;
  size_t data_offset_ = 0;
  size_t mapped_size_ = 0;
  void* mapped_ = nullptr;
};

// Writes a float32 (N, H, W) .npy file from N CV_32F maps of equal size
// (values written as given). Only the tests use it, for .npy fixtures of the
// readers above (`dvso predict` writes KITTI PNGs; no command writes .npy).
void WriteNpyStack(const std::string& path, const std::vector<cv::Mat>& maps);

}  // namespace dvso
