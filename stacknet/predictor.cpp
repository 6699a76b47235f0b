#include "stacknet/predictor.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.h"
#include "stacknet/device.h"
#include "stacknet/post_process.h"

namespace dvso::stacknet {

void PredictorOptions::Check() const {
  Require(device == "auto" || device == "cpu" || device == "cuda", "predictor device must be auto, cpu or cuda");
  Require(num_threads >= 0, "predictor num_threads must be >= 0");
}

TorchDisparityPredictor::TorchDisparityPredictor(const std::string& model_path, const PredictorOptions& options)
    : options_(options), device_(SelectDevice(options.device, options.num_threads)) {
  options_.Check();
  try {
    module_ = torch::jit::load(model_path, device_);
  } catch (const c10::Error& e) {
    throw Error(model_path, std::string("cannot load TorchScript model: ") + e.what_without_backtrace());
  }
  module_.eval();
  RequireFile(module_.hasattr("input_width") && module_.hasattr("input_height"), model_path,
              "not a dvso export (no input_width/input_height attributes)");
  input_width_ = static_cast<int>(module_.attr("input_width").toInt());
  input_height_ = static_cast<int>(module_.attr("input_height").toInt());
}

DisparityPair TorchDisparityPredictor::PredictImage(const cv::Mat& image) {
  Require(!image.empty() && image.depth() == CV_8U, "predictor needs an 8-bit grey or BGR image");
  cv::Mat rgb, resized, as_float;
  cv::cvtColor(image, rgb, image.channels() == 1 ? cv::COLOR_GRAY2RGB : cv::COLOR_BGR2RGB);
  cv::resize(rgb, resized, cv::Size(input_width_, input_height_), 0, 0, cv::INTER_AREA);
  resized.convertTo(as_float, CV_32FC3, 1.0 / 255.0);
  torch::Tensor input =
      torch::from_blob(as_float.data, {1, input_height_, input_width_, 3}, torch::kFloat32).permute({0, 3, 1, 2});
  if (options_.post_process) input = torch::cat({input, input.flip({3})}, 0);
  input = input.contiguous().to(device_);
  torch::NoGradGuard no_grad;
  const auto outputs = module_.forward({input}).toTuple();
  torch::Tensor left = outputs->elements()[0].toTensor();
  torch::Tensor right = outputs->elements()[1].toTensor();
  if (options_.post_process) {
    left = BlendPostProcess(left.narrow(0, 0, 1), left.narrow(0, 1, 1).flip({3}));
    right = right.narrow(0, 0, 1);
  }
  auto to_mat = [&](const torch::Tensor& t) {
    const torch::Tensor cpu = t.to(torch::kCPU).contiguous().squeeze();
    cv::Mat network(input_height_, input_width_, CV_32F, cpu.data_ptr<float>());
    // Disparity scales with the width when resizing to the image resolution.
    return ResizeDisparity(network.clone(), image.cols, image.rows);
  };
  return DisparityPair{to_mat(left), to_mat(right)};
}

cv::Mat ColorizeDisparity(const cv::Mat& disparity, double max_disparity) {
  double scale = max_disparity;
  if (scale <= 0) {
    std::vector<float> values(disparity.begin<float>(), disparity.end<float>());
    if (!values.empty()) {
      const size_t k = values.size() * 99 / 100;
      std::nth_element(values.begin(), values.begin() + k, values.end());
      scale = values[k];
    }
  }
  if (!(scale > 0)) scale = 1;
  cv::Mat normalized;
  disparity.convertTo(normalized, CV_8U, 255.0 / scale);
  cv::Mat colored;
  cv::applyColorMap(normalized, colored, cv::COLORMAP_MAGMA);
  return colored;
}

}  // namespace dvso::stacknet
