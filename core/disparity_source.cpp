#include "core/disparity_source.h"

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "core/fs_util.h"

namespace dvso {

namespace {
bool IsNpy(const std::string& path) { return std::filesystem::path(path).extension() == ".npy"; }
}  // namespace

cv::Mat ResizeDisparity(const cv::Mat& disparity, int width, int height) {
  if (disparity.cols == width && disparity.rows == height) return disparity;
  cv::Mat out;
  // Nearest keeps invalid (0) pixels from bleeding into valid ones.
  cv::resize(disparity, out, cv::Size(width, height), 0, 0, cv::INTER_NEAREST);
  out *= static_cast<double>(width) / disparity.cols;
  return out;
}

FileDisparitySource::FileDisparitySource(std::string left_path, std::string right_path)
    : left_path_(std::move(left_path)), right_path_(std::move(right_path)) {
  Require(IsNpy(left_path_) == IsNpy(right_path_), "left and right disparities must both be .npy or both folders");
  if (IsNpy(left_path_)) {
    left_npy_ = std::make_unique<NpyDisparityStack>(left_path_);
    right_npy_ = std::make_unique<NpyDisparityStack>(right_path_);
    RequireFile(left_npy_->size() == right_npy_->size(), right_path_, "left and right stacks differ in length");
  } else {
    RequireFile(std::filesystem::is_directory(left_path_), left_path_, "disparity folder does not exist");
    RequireFile(std::filesystem::is_directory(right_path_), right_path_, "disparity folder does not exist");
  }
}

DisparityPair FileDisparitySource::Predict(int index, const cv::Mat& left_image) {
  const int w = left_image.cols, h = left_image.rows;
  DisparityPair pair;
  if (left_npy_) {
    pair.left = left_npy_->Frame(index, w, h);
    pair.right = right_npy_->Frame(index, w, h);
  } else {
    pair.left = ResizeDisparity(ReadKittiMapPng(JoinPath(left_path_, FrameFileName(index, ".png"))), w, h);
    pair.right = ResizeDisparity(ReadKittiMapPng(JoinPath(right_path_, FrameFileName(index, ".png"))), w, h);
  }
  return pair;
}

}  // namespace dvso
