// Estimates a lens's radial vignetting from a sequence, without a calibration target: the same scene point
// seen in several keyframes at different distances from the image centre. Model of one observation (a
// point p sampled in frame f at rho^2, RadialPosition):
//
//   I_pf = a_f * V(rho_pf^2) * R_p + b_f                       (the camera model of DSO's photometric
//                                                                calibration, affine exposure per frame)
//
// with R_p the point's radiance, a_f and b_f the frame's exposure gain and offset, and V = RadialVignette
// (core/vignette.h, V(0) = 1). Robust (Huber) least squares by Levenberg-Marquardt; each point's radiance
// is eliminated per step (a Schur complement, one scalar per point), so the dense system has only the
// frames' 2 F - 1 exposure unknowns (a_0 = 1 fixes the scale shared by a and R) and the coefficients.
// This is the offline form of the idea of Bergmann, Wang and Cremers, "Online Photometric Calibration of
// Auto Exposure Video for Realtime Visual Odometry and SLAM" (RA-L 2018), which fits the same model.
#pragma once

#include <vector>

#include "core/vignette.h"

namespace dvso::vo {

constexpr double kVignetteProfileBinWidth = 0.05;
constexpr int kVignetteProfileMinSamples = 20;

struct VignetteObservation {
  int point = 0;         // 0 .. num_points - 1
  int frame = 0;         // 0 .. num_frames - 1
  double rho_sq = 0;     // RadialPosition::Sq of the sampled pixel
  double intensity = 0;  // grey level there (after the inverse response, if one is known)
};

struct VignetteFitOptions {
  int num_coefficients = 2;       // V = 1 + c_1 rho^2 + c_2 rho^4 (rho = 1 at the half diagonal)
  double huber_threshold = 5.0;   // grey levels: residuals above weigh less (occlusions, misprojections)
  int max_iterations = 300;       // Levenberg-Marquardt steps
  int min_observations_per_point = 3;  // a point seen fewer times says nothing about V and is left out
  void Check() const;
};

struct VignetteFit {
  RadialVignette vignette;
  std::vector<double> gain, bias;   // a_f, b_f per frame (a_0 = 1)
  int observations = 0;             // used (of points with enough observations)
  int points = 0;
  int iterations = 0;
  double rms = 0;                   // root mean square residual at the end (grey levels, all used observations)
  double rms_without_vignette = 0;  // the same model fitted with V = 1: how much the vignette explains
  // The data as a vignette profile: rho bins of width kVignetteProfileBinWidth from 0, and in each the
  // median of (I - b_f) / (a_f R_p) over its observations (NaN where a bin has fewer than
  // kVignetteProfileMinSamples): what V looks like without the polynomial.
  std::vector<double> profile_rho, profile_ratio;
};

// Throws dvso::Error when no point has enough observations or an index is out of range.
VignetteFit FitVignette(const std::vector<VignetteObservation>& observations, int num_points, int num_frames,
                        const VignetteFitOptions& options = {});

}  // namespace dvso::vo
