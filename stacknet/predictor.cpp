#include "stacknet/predictor.h"

#include <algorithm>
#include <filesystem>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.h"
#include "stacknet/device.h"
#include "stacknet/export.h"
#include "stacknet/post_process.h"

namespace dvso::stacknet {

void PredictorOptions::Check() const {
  Require(device == "auto" || device == "cpu" || device == "cuda", "predictor device must be auto, cpu or cuda");
  Require(num_threads >= 0, "predictor num_threads must be >= 0");
}

TorchDisparityPredictor::TorchDisparityPredictor(const std::string& model_path, const PredictorOptions& options)
    : model_path_(model_path), options_(options), device_(SelectDevice(options.device, options.num_threads)) {
  options_.Check();
  RequireFile(std::filesystem::is_regular_file(model_path), model_path, "model file does not exist");
  LoadedModel loaded = LoadModel(model_path, device_);
  module_ = std::move(loaded.module);
  module_.eval();
  UseInferenceLayout(module_, device_);
  RequireFile(module_.hasattr("input_width") && module_.hasattr("input_height"), model_path,
              "not a dvso export (no input_width/input_height attributes)");
  metadata_ = loaded.metadata;
  input_width_ = metadata_.input_width;
  input_height_ = metadata_.input_height;
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
  // The permuted NHWC image already is channels-last: on CPU no copy is made here.
  input = ToConvolutionLayout(input, device_).to(device_);
  torch::NoGradGuard no_grad;
  c10::IValue output;
  try {
    output = module_.forward({input});
  } catch (const c10::Error& e) {
    throw Error(model_path_, std::string("model forward failed: ") + e.what_without_backtrace());
  }
  const auto expected_map = [&](const c10::IValue& v) {
    if (!v.isTensor()) return false;
    const torch::Tensor t = v.toTensor();
    return t.dim() == 4 && t.size(1) == 1 && t.size(2) == input_height_ && t.size(3) == input_width_ &&
           t.scalar_type() == torch::kFloat32;
  };
  RequireFile(output.isTuple() && output.toTuple()->elements().size() == 2 &&
                  expected_map(output.toTuple()->elements()[0]) && expected_map(output.toTuple()->elements()[1]),
              model_path_, "model output is not 2 float maps (left, right disparity) of shape Nx1xHxW");
  torch::Tensor left = output.toTuple()->elements()[0].toTensor();
  torch::Tensor right = output.toTuple()->elements()[1].toTensor();
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
