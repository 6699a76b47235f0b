#include "core/vignette.h"

#include <algorithm>
#include <cmath>

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

cv::Mat RadialVignette::Image(const PinholeCamera& camera) const {
  const RadialPosition rho(camera);
  cv::Mat v(camera.height, camera.width, CV_32FC1);
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) v.at<float>(y, x) = static_cast<float>(At(rho.Sq(x, y)));
  double max_v = 0;
  cv::minMaxLoc(v, nullptr, &max_v);
  Require(max_v > 0, "vignette is zero over the whole image");
  return v / max_v;
}

void RadialVignette::WritePng(const std::string& path, const PinholeCamera& camera) const {
  cv::Mat u16;
  Image(camera).convertTo(u16, CV_16UC1, 65535.0);  // rounds and saturates
  WriteImageAtomically(path, u16);
}

}  // namespace dvso
