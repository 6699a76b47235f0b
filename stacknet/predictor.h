// Inference with an exported TorchScript model: images of any size in,
// disparity maps (pixels at the image's resolution) out. Implements the core
// DisparitySource interface so the odometry can use the network (DVSO).
#pragma once

#include <torch/script.h>

#include <opencv2/core.hpp>
#include <string>

#include "core/disparity_conversion.h"
#include "core/disparity_source.h"

namespace dvso::stacknet {

struct PredictorOptions {
  std::string device = "auto";  // auto | cpu | cuda
  bool post_process = false;    // Godard's flip-and-blend for the left disparity
  int num_threads = 0;          // CPU threads; 0 = hardware cores
  void Check() const;
};

class TorchDisparityPredictor : public DisparitySource {
 public:
  TorchDisparityPredictor(const std::string& model_path, const PredictorOptions& options = {});
  // Left/right disparities (CV_32F, pixels) at the resolution of `image`
  // (grey or BGR 8 bit). Values scale with width when resizing.
  DisparityPair PredictImage(const cv::Mat& image);
  DisparityPair Predict(int index, const cv::Mat& left_image) override { return PredictImage(left_image); }
  int input_width() const { return input_width_; }
  int input_height() const { return input_height_; }
  // What `dvso export` stored in the file (training camera, input size, config).
  const ModelMetadata& metadata() const { return metadata_; }

 private:
  std::string model_path_;
  ModelMetadata metadata_;
  torch::jit::Module module_;
  PredictorOptions options_;
  torch::Device device_;
  int input_width_ = 0, input_height_ = 0;
};

// Colour-mapped visualisation of a disparity map (BGR 8 bit, magma-like
// OpenCV colour map, normalised by `max_disparity` or by the map's 99th percentile when <= 0).
cv::Mat ColorizeDisparity(const cv::Mat& disparity, double max_disparity = 0);

}  // namespace dvso::stacknet
