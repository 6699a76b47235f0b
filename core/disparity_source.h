// Where the odometry gets predicted disparities from (DVSO: depth init from
// D^L, virtual stereo term with D^R). vo/ only sees this interface; files are
// read by the implementations below, a TorchScript predictor lives in stacknet/.
#pragma once

#include <memory>
#include <opencv2/core.hpp>
#include <string>

#include "core/disparity_io.h"

namespace dvso {

struct DisparityPair {
  cv::Mat left;   // D^L: CV_32F, pixels at the sequence's image resolution, <= 0 = unknown
  cv::Mat right;  // D^R: CV_32F, same size; right image x = left x - d
};

class DisparitySource {
 public:
  virtual ~DisparitySource() = default;
  // Predicted disparities for frame `index` given its left image (CV_8UC1 or
  // CV_8UC3); maps are returned at the image's resolution. Throws dvso::Error.
  virtual DisparityPair Predict(int index, const cv::Mat& left_image) = 0;
};

// Reads precomputed maps: either two folders of KITTI uint16 PNGs
// (left_dir/%06d.png, right_dir/%06d.png) or two .npy stacks normalised by
// width (monodepth convention). Maps of another size are resized (values
// scaled with the width).
class FileDisparitySource : public DisparitySource {
 public:
  FileDisparitySource(std::string left_path, std::string right_path);
  DisparityPair Predict(int index, const cv::Mat& left_image) override;

 private:
  std::string left_path_, right_path_;
  std::unique_ptr<NpyDisparityStack> left_npy_, right_npy_;
};

// Resizes a disparity map to width x height, scaling its values with the width.
cv::Mat ResizeDisparity(const cv::Mat& disparity, int width, int height);

}  // namespace dvso
