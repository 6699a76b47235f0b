#include "core/vignette.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/image_file.h"

namespace dvso {

double RadialVignette::At(double rho_sq) const {
  double v = 1.0, power = 1.0;
  for (double c : coefficients) {
    power *= rho_sq;
    v += c * power;
  }
  return std::max(0.0, v);
}

double RadialVignette::Derivative(int i, double rho_sq) const {
  if (At(rho_sq) <= 0) return 0.0;
  return std::pow(rho_sq, i + 1);
}

namespace {

// V at every pixel in double, divided by its maximum when that exceeds 1 (a lens brighter off-centre). A
// falling lens stays as V: its brightest pixel is within 1e-7 of 1 (the principal point lies between pixels),
// and the simulator's vignette.png keeps exactly the values it had before this function existed.
cv::Mat NormalisedImage(const RadialVignette& vignette, const PinholeCamera& camera) {
  const RadialPosition rho(camera);
  cv::Mat v(camera.height, camera.width, CV_64FC1);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) v.at<double>(y, x) = vignette.At(rho.Sq(x, y));
  double max_v = 0;
  cv::minMaxLoc(v, nullptr, &max_v);
  Require(max_v > 0, "vignette is zero over the whole image");
  return max_v > 1.0 ? cv::Mat(v / max_v) : v;
}

}  // namespace

cv::Mat RadialVignette::Image(const PinholeCamera& camera) const {
  cv::Mat v;
  NormalisedImage(*this, camera).convertTo(v, CV_32F);
  return v;
}

void RadialVignette::WritePng(const std::string& path, const PinholeCamera& camera) const {
  const cv::Mat v = NormalisedImage(*this, camera);
  cv::Mat u16(v.size(), CV_16UC1);
  for (int y = 0; y < v.rows; ++y)
    for (int x = 0; x < v.cols; ++x) u16.at<uint16_t>(y, x) = static_cast<uint16_t>(std::lround(65535.0 * v.at<double>(y, x)));
  WriteImageAtomically(path, u16, {cv::IMWRITE_PNG_COMPRESSION, 1});
}

}  // namespace dvso
