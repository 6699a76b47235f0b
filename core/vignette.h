// A lens's radial vignetting V(x): the fraction of the irradiance at the image centre that reaches pixel x.
// One model for the simulator's camera (core/simulator_render.cpp), the vignette.png it writes, the stereo
// brightness transfer's radial term (vo/frame/stereo_brightness.h) and the fall-off that
// `dvso calibrate-vignette` estimates from a sequence (vo/frame/vignette_fit.h).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/camera.h"

namespace dvso {

// rho^2 = ((u - cx)^2 + (v - cy)^2) / r_corner^2 with r_corner^2 = (width^2 + height^2) / 4 (the image's
// half diagonal): 0 at the principal point, about 1 in the corners. The one implementation of rho^2: the
// simulator, the vignette fit, the stereo search and the brightness fit use it in double, the static stereo
// residual in float (BasicRadialPosition<float>, vo/optimization/residuals.h).
template <typename Scalar>
struct BasicRadialPosition {
  Scalar cx = 0, cy = 0, inv_corner_sq = 0;
  BasicRadialPosition() = default;
  explicit BasicRadialPosition(const PinholeCamera& camera)
      : cx(static_cast<Scalar>(camera.cx)),
        cy(static_cast<Scalar>(camera.cy)),
        inv_corner_sq(static_cast<Scalar>(4.0 / (static_cast<double>(camera.width) * camera.width +
                                                 static_cast<double>(camera.height) * camera.height))) {}
  Scalar Sq(Scalar u, Scalar v) const { return ((u - cx) * (u - cx) + (v - cy) * (v - cy)) * inv_corner_sq; }
};
using RadialPosition = BasicRadialPosition<double>;

// V(rho^2) = max(0, 1 + sum_i coefficients[i] * rho^(2 (i + 1))): 1 at the principal point. The simulator's
// lens is {-strength} (a fall-off of `strength` at the half diagonal).
struct RadialVignette {
  std::vector<double> coefficients;

  double At(double rho_sq) const;
  // d V / d coefficients[i] = rho^(2 (i + 1)) where V > 0 (the fit's Jacobian).
  double Derivative(int i, double rho_sq) const;
  // V at every pixel of `camera`'s image as CV_32F, divided by its maximum over the image when that exceeds 1
  // (DSO's and PhotometricCalibration's convention: the brightest pixel is 1; a falling lens's brightest
  // pixel is already within 1e-7 of it).
  cv::Mat Image(const PinholeCamera& camera) const;
  // Image() as a uint16 PNG (round(65535 V), computed in double), the format `vignette_file` reads. Throws dvso::Error naming the path.
  void WritePng(const std::string& path, const PinholeCamera& camera) const;
};

}  // namespace dvso
