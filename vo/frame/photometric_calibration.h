// Optional photometric calibration as in DSO: an inverse camera response
// G^-1 (256 values, "pcalib.txt": one line of 256 floats) and a vignette
// image V (8- or 16-bit PNG, normalised so that its maximum is 1). Images are
// corrected to irradiance B = G^-1(I) / V before building the pyramid; the
// exposure time (if known) is handled by the caller via ImagePyramid.
#pragma once

#include <array>
#include <opencv2/core.hpp>
#include <string>

namespace dvso::vo {

class PhotometricCalibration {
 public:
  // Identity response, no vignette.
  PhotometricCalibration();
  // Loads "gamma_file" (256 values, monotonically increasing, rescaled to
  // [0, 255]) and optionally "vignette_file" (empty = none). Throws dvso::Error.
  static PhotometricCalibration Load(const std::string& gamma_file, const std::string& vignette_file);

  // Converts an 8-bit image to a float irradiance image (CV_32F, 0..255 range).
  cv::Mat Correct(const cv::Mat& image_u8) const;

  const std::array<float, 256>& inverse_response() const { return inverse_response_; }
  bool has_vignette() const { return !inverse_vignette_.empty(); }
  cv::Size vignette_size() const { return inverse_vignette_.size(); }  // 0 x 0 without a vignette

 private:
  std::array<float, 256> inverse_response_{};
  cv::Mat inverse_vignette_;  // CV_32F, 1 / V, empty when no vignette
};

}  // namespace dvso::vo
