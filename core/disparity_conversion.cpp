#include "core/disparity_conversion.h"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/error.h"

namespace dvso {

std::string ModelMetadata::ToJson() const {
  nlohmann::json j;
  j["input_width"] = input_width;
  j["input_height"] = input_height;
  j["baseline"] = baseline;
  j["fx_over_width"] = fx_over_width;
  j["config_name"] = config_name;
  j["model_kind"] = model_kind;
  j["tuned_baseline"] = tuned_baseline;
  j["tuned_on"] = tuned_on;
  return j.dump(2);
}

ModelMetadata ModelMetadata::FromJson(const std::string& json, const std::string& source) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(json);
  } catch (const nlohmann::json::exception& e) {
    throw Error(source, std::string("model metadata is not valid JSON: ") + e.what());
  }
  RequireFile(j.is_object(), source, "model metadata must be a JSON object");
  ModelMetadata m;
  try {
    for (const auto& [key, value] : j.items()) {
      if (key == "input_width") m.input_width = value.get<int>();
      else if (key == "input_height") m.input_height = value.get<int>();
      else if (key == "baseline") m.baseline = value.get<double>();
      else if (key == "fx_over_width") m.fx_over_width = value.get<double>();
      else if (key == "config_name") m.config_name = value.get<std::string>();
      else if (key == "model_kind") m.model_kind = value.get<std::string>();
      else if (key == "tuned_baseline") m.tuned_baseline = value.get<double>();
      else if (key == "tuned_on") m.tuned_on = value.get<std::string>();
      else throw Error(source, "unknown model metadata key '" + key + "'");
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(source, std::string("model metadata has a value of the wrong type: ") + e.what());
  }
  RequireFile(m.baseline >= 0 && m.fx_over_width >= 0 && m.tuned_baseline >= 0, source,
              "model metadata: negative baseline or fx/width");
  return m;
}

double InverseDepthFromDisparity(double disparity_px, double fx, double virtual_baseline) {
  Require(fx > 0 && virtual_baseline > 0, "InverseDepthFromDisparity: fx and the virtual baseline must be > 0");
  if (!(disparity_px > 0) || !std::isfinite(disparity_px)) return 0.0;
  return disparity_px / (fx * virtual_baseline);
}

double VirtualBaselineOfModel(const ModelMetadata& model, bool tuned) {
  Require(model.has_camera(), "the model carries no training camera (baseline, fx/width): pass --virtual-baseline");
  return tuned && model.tuned_baseline > 0 ? model.tuned_baseline : model.baseline;
}

float LeftRightDisparityError(const cv::Mat& disparity_left, const cv::Mat& disparity_right, int u, int v) {
  constexpr float kInvalid = std::numeric_limits<float>::infinity();
  if (u < 0 || v < 0 || u >= disparity_left.cols || v >= disparity_left.rows) return kInvalid;
  const float d_left = disparity_left.at<float>(v, u);
  if (!(d_left > 0) || !std::isfinite(d_left)) return kInvalid;
  const float x = static_cast<float>(u) - d_left;  // p' = p - (D^L(p), 0)
  if (!(x >= 0.0f) || x > disparity_right.cols - 1) return kInvalid;
  const int x0 = std::min(static_cast<int>(x), disparity_right.cols - 2);
  const float fx = x - x0;
  // Only taps with weight enter: p' on a pixel centre needs that pixel alone.
  const float r0 = fx < 1.0f ? disparity_right.at<float>(v, x0) : 0.0f;
  const float r1 = fx > 0.0f ? disparity_right.at<float>(v, x0 + 1) : 0.0f;
  if ((fx < 1.0f && !(r0 > 0 && std::isfinite(r0))) || (fx > 0.0f && !(r1 > 0 && std::isfinite(r1)))) return kInvalid;
  return std::abs(d_left - ((1.0f - fx) * r0 + fx * r1));
}

cv::Mat SanitizeDisparity(const cv::Mat& disparity) {
  Require(disparity.type() == CV_32FC1, "SanitizeDisparity: expected a CV_32FC1 map");
  cv::Mat out = disparity.clone();
  for (int y = 0; y < out.rows; ++y) {
    float* row = out.ptr<float>(y);
    for (int x = 0; x < out.cols; ++x) {
      if (!(row[x] > 0) || !std::isfinite(row[x])) row[x] = 0.0f;
    }
  }
  return out;
}

}  // namespace dvso
