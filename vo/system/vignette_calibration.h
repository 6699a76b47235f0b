// `dvso calibrate-vignette`: a lens's vignetting from an ordinary recording (KITTI ships none). The
// odometry runs over the sequence as `dvso odometry` would; every marginalised point is then projected,
// with the final keyframe poses, into the keyframes around its host, its grey level sampled there, and
// FitVignette (vo/frame/vignette_fit.h) finds the radial fall-off that, with a per-keyframe affine
// exposure, explains how a point's brightness changes as it moves across the image. The result is a
// `vignette_file` for the odometry (`vignette:` of the config, exact PhotometricCalibration format).
#pragma once

#include <string>

#include "core/camera.h"
#include "core/sequence.h"
#include "vo/frame/vignette_fit.h"
#include "vo/system/odometry_options.h"
#include "vo/system/sequence_runner.h"

namespace dvso::vo {

struct VignetteCalibrationOptions {
  int neighbour_keyframes = 5;   // a point is sampled in the keyframes up to this many before and after its host
                                 // (the fit's dense system couples keyframes this far apart; see --count)
                                 // (DSO's window: the keyframes it was optimised in; farther ones see it from
                                 // far, occluded or through a drifted pose)
  double blur_fraction = 0.0024;  // Gaussian blur before sampling, sigma as a fraction of the image width (3 px at
                                  // KITTI's 1241): points sit on strong gradients, where a sub-pixel projection
                                  // error would otherwise change the grey level a lot, while the fall-off is
                                  // smooth. Relative to the width because the scene's scale per pixel is: on
                                  // a lens of 0.70, 3 px found 0.70-0.71 at 1241x376 but 0.79 at 640x192,
                                  // 1.5 px found 0.73-0.79 at 1241x376 but 0.75 at 640x192 (docs/vignette.md)
  int border = 8;                // px kept clear of the image edges (the blur's and the projection's margin)
  double min_intensity = 8;      // grey levels outside [min, max] (after blurring) are dropped: black or
  double max_intensity = 247;    // saturated pixels do not follow the model
  double max_sample_gradient = 5;  // grey levels / px: a sample where the blurred image is steeper is dropped (0 =
                                   // keep all). There a projection error of a fraction of a pixel changes the grey
                                   // level by more than the fall-off does, and not evenly: errors grow towards the
                                   // edges (near points) and silhouettes mix in the bright sky. Measured: a flat
                                   // lens read V(1) = 1.022 without, 1.0005 with it (640x192)
  int min_good_residuals = 3;    // a point's active temporal residuals when marginalised (label writer's idea)
  int max_points = 200000;       // more points are thinned evenly (memory and fit time)
  VignetteFitOptions fit;
  void Check() const;
};

struct VignetteCalibration {
  VignetteFit fit;
  PinholeCamera camera;   // the left camera the vignette belongs to
  int keyframes = 0;      // keyframes sampled (the fit's frames)
  int segments = 0;       // tracking segments (1 + resets); only the longest one is sampled
  SequenceRunSummary run;
};

// Runs the odometry (its outputs go to out_dir as for `dvso odometry`), collects the points and fits.
// options.vignette_file must be empty (the raw images are what is calibrated); options.gamma_file, when
// given, is applied to the sampled grey levels too. Throws dvso::Error.
VignetteCalibration CalibrateVignette(const SequenceReader& sequence, const OdometryOptions& options,
                                      OdometryMode mode, const std::string& out_dir, const SequenceRunOptions& run,
                                      const VignetteCalibrationOptions& calibration = {});

// Writes vignette.png (the fitted V, maximum 1, uint16: the `vignette_file` format), vignette_fit.yaml
// (coefficients, fall-off at the corner, residuals, counts) and vignette_profile.png (the data's profile
// against the fitted curve) into out_dir.
void WriteVignetteCalibration(const std::string& out_dir, const VignetteCalibration& calibration);

}  // namespace dvso::vo
