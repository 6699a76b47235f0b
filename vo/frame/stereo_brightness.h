// Brightness transfer between the two images of a stereo pair.
//
// The two sensors of a real rig differ in gain and black level, and with
// independent auto exposure the difference changes from frame to frame. The
// static stereo term (Stereo DSO) compares the right image with the left one,
// so it needs that transfer: Stereo DSO (Wang et al. 2017) gives each image its
// own affine brightness for this reason. Without it, a right camera 15 %
// brighter with a black level 6 grey levels higher made nearly every static
// stereo match fail and Stereo DSO lost 99 of 100 frames (docs/labels.md,
// "Session 27"). On the real KITTI 2015 pair the fit is x0.985 + 5.4.
//
// Two estimators, both a line fit y = gain x + bias (FitBrightnessTransfer, orthogonal):
// - Before any point is matched (the matching needs a transfer), from the
//   images alone: the two views see nearly the same scene, so their intensity
//   distributions differ mainly by the transfer, and matching their quantiles
//   needs no correspondence: Q_right(q) = gain * Q_left(q) + bias. Parallax and
//   the side strips make it a rough start (gain off by up to ~15 % on the
//   simulator's worlds), good enough for many matches to succeed.
// - From the matches (the keyframe's static stereo matches, system_keyframes.cpp):
//   host pattern intensities against the right image at the match. These are
//   correspondences, so the fit is exact up to noise and wrong matches (Huber).
// The odometry starts each stereo keyframe from the previous keyframe's transfer
// (quantiles for the first one), matches, refits from the matches and, when the
// transfer moved, matches again.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include "core/camera.h"
#include "core/vignette.h"
#include "vo/frame/image_pyramid.h"

namespace dvso::vo {

// I_right(p') ~ gain * (1 + radial * rho^2) * I_left(p) + bias at a match p -> p' (the immature point's
// (a, b) convention with a = Gain(rho^2); the static stereo residual's affine_scale = gain, radial_gain =
// radial, b_target = bias, b_host = 0). rho = |p - principal point| / r_corner (RadialPosition::Sq) at the
// LEFT pixel p: the radial term absorbs a difference in the two lenses' vignetting (V_right(p') / V_left(p),
// first order in rho^2; the disparity's shift of p' against p is left to the fit's mean). Session 28 measured
// that a right lens with a fall-off 0.3 weaker at the corners cost 31 % of the labels without it.
struct StereoBrightness {
  double gain = 1.0;
  double bias = 0.0;
  double radial = 0.0;
  double Gain(double rho_sq) const { return gain * (1.0 + radial * rho_sq); }
};

// rho^2: RadialPosition (core/vignette.h).

struct StereoBrightnessOptions {
  bool estimate = true;             // false: identical cameras assumed (gain 1, bias 0; the behaviour until session 27)
  int sample_step = 4;              // px: every sample_step-th pixel in x and y (29k samples at 1241x376)
  double border_fraction = 0.1;     // width fraction of the side the other camera does not see, left out of each image
  double min_quantile = 0.05;       // lowest quantile level matched (below: noise and dark saturation)
  double max_quantile = 0.95;       // highest quantile level matched (above: sky, bright saturation)
  int num_quantiles = 37;           // quantile levels, evenly spaced in [min_quantile, max_quantile]
  double huber_threshold = 4.0;     // Huber threshold of both line fits' residuals (intensity units of level 0)
  double max_gain_ratio = 3.0;      // a fit outside [1 / this, this] means the views disagree: identity is used
  int min_matched_points = 50;      // fewer unambiguous static stereo matches: the transfer is not refitted
  int max_matching_passes = 3;      // match, refit, match again while the transfer moves (first keyframe: 2-3)
  double rematch_change = 1.0;      // a refit that moves the transfer by more than this anywhere in the samples'
                                    // intensity range (intensity units) triggers another matching pass
  bool estimate_radial = false;     // also fit the radial gain term (lenses with different vignetting; off by
                                    // default: on identical lenses its fit noise costs a little, docs/labels.md)
  double max_radial = 0.8;          // a fitted |radial| above this is implausible: the fit is refused
  int radial_pool_keyframes = 1000; // the radial term is a lens property: each keyframe uses the median of its own
                                    // fit and those of up to this many earlier keyframes (0: its own fit alone;
                                    // a median of 50 still wandered from -0.05 to +0.065 with the scene, docs/labels.md
                                    // "Session 29")
  void Check() const;
};

// Line y = gain * x + bias by orthogonal least squares (x and y equally noisy: the slope of the
// centred sums, g = (Syy - Sxx + sqrt((Syy - Sxx)^2 + 4 Sxy^2)) / (2 Sxy)), reweighted with Huber
// weights of the vertical residuals (threshold in y's units).
// None when fewer than 3 samples, no spread in x, or a gain outside [1 / max_gain_ratio, max_gain_ratio].
std::optional<StereoBrightness> FitBrightnessTransfer(const std::vector<double>& x, const std::vector<double>& y,
                                       double huber_threshold, double max_gain_ratio);

// The line fit above with the radial term: y = gain (1 + radial rho_sq) x + bias. radial from the joint
// Huber-reweighted least squares in (gain, gain * radial, bias), then gain and bias by the orthogonal
// line fit on (x (1 + radial rho_sq), y). None where either fit refuses, rho_sq has no spread, or
// |radial| > max_radial.
std::optional<StereoBrightness> FitRadialBrightnessTransfer(const std::vector<double>& x, const std::vector<double>& y,
                                                            const std::vector<double>& rho_sq, double huber_threshold,
                                                            double max_gain_ratio, double max_radial);

// The two steps of FitRadialBrightnessTransfer one by one: the radial coefficient (step 1; none where
// that fit refuses), and gain and bias for a given radial coefficient (step 2; none as FitBrightnessTransfer).
std::optional<double> FitRadialTerm(const std::vector<double>& x, const std::vector<double>& y,
                                    const std::vector<double>& rho_sq, double huber_threshold, double max_radial);
std::optional<StereoBrightness> FitBrightnessTransferAtRadial(const std::vector<double>& x, const std::vector<double>& y,
                                                              const std::vector<double>& rho_sq, double radial,
                                                              double huber_threshold, double max_gain_ratio);

// The radial term pooled over keyframes. It is a property of the two lenses, constant in time (gain
// and bias are not: auto exposure moves them between keyframes), while one keyframe's fit of it is
// noisy and pulled by the scene (identical lenses: -0.049 to +0.012 between the keyframes of one
// world, docs/labels.md "Session 28"; even a median over 50 keyframes still wandered from -0.05 to
// +0.065 along a 500-frame world, "Session 29"). The median over many keyframes is robust to the
// scenes of a few, and a keyframe whose own fit is refused (its matches have too little spread in
// rho^2) still gets the pooled term. Memory is bounded by the capacity.
class RadialTermPool {
 public:
  explicit RadialTermPool(int capacity = 0);
  // Stores a keyframe's own fit; the oldest goes beyond the capacity (capacity 0 stores nothing).
  void Add(double keyframe_radial);
  // Median of the stored fits and `current` (the mean of the two middle values for an even count).
  double MedianWith(double current) const;
  // Median of the stored fits alone; requires size() > 0.
  double Median() const;
  int size() const { return static_cast<int>(fits_.size()); }

 private:
  int capacity_;
  std::deque<double> fits_;
};

// Largest |Gain_b(rho^2) I + bias_b - Gain_a(rho^2) I - bias_a| over I in [low, high] and rho^2 in [0, 1]:
// how far two transfers disagree on the intensities that occur (gain and bias of a fit trade against
// each other, so comparing them one by one would compare extrapolations to intensity 0). Bilinear in
// (I, rho^2), so the largest magnitude is at a corner.
double BrightnessTransferChange(const StereoBrightness& a, const StereoBrightness& b, double low, double high);

// The open intensity interval of an image's pixels that are not clipped: its darkest and brightest
// level-0 intensities, each moved inwards by kClipMargin. A black or saturated pixel says nothing
// about the transfer (all of them lie on one side of the line), so the match fit leaves them out.
struct UnclippedRange {
  static constexpr float kClipMargin = 0.5f;  // intensity units: within this of an image's extreme = clipped
  float low = 0, high = 0;
  bool Contains(float intensity) const { return intensity > low && intensity < high; }
};
UnclippedRange UnclippedIntensityRange(const PyramidLevel& level);

// The transfer of the pair (left, right) from quantiles, both level 0 of their pyramids (same size).
// Returns the identity when options.estimate is false, when too few quantile
// levels are usable (flat images), or when the fitted gain is implausible.
StereoBrightness EstimateStereoBrightness(const PyramidLevel& left, const PyramidLevel& right,
                                          const StereoBrightnessOptions& options);

}  // namespace dvso::vo
