#include "vo/frame/photometric_calibration.h"

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "core/error.h"

namespace dvso::vo {

PhotometricCalibration::PhotometricCalibration() {
  for (int i = 0; i < 256; ++i) inverse_response_[i] = static_cast<float>(i);
}

PhotometricCalibration PhotometricCalibration::Load(const std::string& gamma_file,
                                                    const std::string& vignette_file) {
  PhotometricCalibration calib;
  if (!gamma_file.empty()) {
    std::ifstream in(gamma_file);
    RequireFile(in.good(), gamma_file, "cannot open photometric response file");
    std::vector<double> values;
    double v;
    while (in >> v) values.push_back(v);
    RequireFile(values.size() == 256, gamma_file,
                "expected 256 inverse-response values, found " + std::to_string(values.size()));
    for (int i = 1; i < 256; ++i) {
      RequireFile(values[i] > values[i - 1], gamma_file, "inverse response must increase monotonically");
    }
    // Rescale to [0, 255] so thresholds tuned on raw intensities still apply (DSO does the same).
    const double lo = values.front();
    const double hi = values.back();
    for (int i = 0; i < 256; ++i) calib.inverse_response_[i] = static_cast<float>(255.0 * (values[i] - lo) / (hi - lo));
  }
  if (!vignette_file.empty()) {
    cv::Mat v = cv::imread(vignette_file, cv::IMREAD_UNCHANGED);
    RequireFile(!v.empty(), vignette_file, "cannot read vignette image");
    RequireFile(v.channels() == 1, vignette_file, "vignette must be a single-channel image");
    cv::Mat vf;
    v.convertTo(vf, CV_32F);
    double min_v, max_v;
    cv::minMaxLoc(vf, &min_v, &max_v);
    RequireFile(max_v > 0 && min_v > 0, vignette_file, "vignette must be strictly positive");
    vf /= max_v;
    calib.inverse_vignette_ = 1.0f / vf;
  }
  return calib;
}

cv::Mat PhotometricCalibration::Correct(const cv::Mat& image_u8) const {
  Require(image_u8.type() == CV_8UC1, "PhotometricCalibration::Correct expects CV_8UC1");
  cv::Mat out(image_u8.size(), CV_32F);
  for (int y = 0; y < image_u8.rows; ++y) {
    const uint8_t* src = image_u8.ptr<uint8_t>(y);
    float* dst = out.ptr<float>(y);
    for (int x = 0; x < image_u8.cols; ++x) dst[x] = inverse_response_[src[x]];
  }
  if (!inverse_vignette_.empty()) {
    Require(inverse_vignette_.size() == image_u8.size(), "vignette size differs from the image size");
    out = out.mul(inverse_vignette_);
  }
  return out;
}

}  // namespace dvso::vo
