// Candidate ("immature") points (DSO's ImmaturePoint): a selected pixel of a
// keyframe whose inverse depth is only known as an interval [idepth_min,
// idepth_max]. Every new frame runs a discrete search along the epipolar line
// segment spanned by the interval (pattern SSD with Huber), refines the best
// match by Gauss-Newton along the line and shrinks the interval to the match
// +- its expected pixel error. Converged, unambiguous points get activated
// (handed to the window); repeated outliers are dropped.
// The same search against the right image (pure x translation) is the static
// stereo matching of Stereo DSO.
#pragma once

#include <Eigen/Core>
#include <array>
#include <limits>

#include "vo/frame/image_pyramid.h"
#include "vo/optimization/residual_pattern.h"

namespace dvso::vo {

struct ImmaturePointOptions {
  double huber_threshold = 9.0;          // Huber threshold of the matching energy (DSO setting_huberTH)
  double outlier_energy_per_pixel = 144.0;  // energy per pattern pixel above which a match is an outlier (DSO 12*12)
  double extra_slack_on_threshold = 1.2; // DSO setting_trace_extraSlackOnTH
  double max_search_fraction = 0.027;    // unbounded intervals: search (w + h) * this pixels (DSO setting_maxPixSearch)
  double step_size = 1.0;                // pixels per search step (DSO setting_trace_stepsize)
  double slack_interval = 1.5;           // skip the search when the interval spans fewer pixels (DSO setting_trace_slackInterval)
  double min_improvement_factor = 2.0;   // skip when the expected error is not this much below the interval (DSO)
  int gn_iterations = 3;                 // Gauss-Newton refinement steps along the line (DSO setting_trace_GNIterations)
  double gn_threshold = 0.1;             // stop the refinement below this step (pixels)
  double min_test_radius = 2.0;          // second-best match must be this far (pixels) from the best (DSO setting_minTraceTestRadius)
  double min_quality = 3.0;              // second best / best energy needed for activation (DSO setting_minTraceQuality)
  double max_pixel_interval = 8.0;       // activation needs an interval shorter than this (pixels)
  void Check() const;
};

enum class TraceStatus : uint8_t {
  kUninitialized,  // never traced
  kGood,           // traced, interval updated
  kOutOfBounds,    // left the image or failed twice: drop the point
  kOutlier,        // no good match this time
  kSkipped,        // interval already small: nothing to gain
  kBadCondition,   // epipolar line parallel to the gradient: no information
};

struct ImmaturePoint {
  int host_id = -1;                     // keyframe id
  float u = 0, v = 0;                   // host pixel (level 0)
  int selection_level = 0;              // pyramid level that selected it
  std::array<float, kPatternSize> color{};   // host intensities at the pattern pixels
  Eigen::Matrix2f gradient_h = Eigen::Matrix2f::Zero();  // sum of g g^T over the pattern (error model)
  float idepth_min = 0.0f;
  float idepth_max = std::numeric_limits<float>::infinity();
  float quality = 10000.0f;             // second-best / best energy of the last search
  float last_pixel_interval = 1000.0f;  // pixel length of the interval at the last search
  float last_energy = 0.0f;
  TraceStatus last_status = TraceStatus::kUninitialized;

  // Creates the point from the host image; returns false when the pattern
  // does not fit or has no gradient.
  bool Initialize(const PyramidLevel& host, int host_id, float u, float v, int selection_level);

  // DVSO depth initialisation (paper section 4): the search interval becomes
  // idepth * [1 - relative_range, 1 + relative_range] around the predicted
  // inverse depth, so the epipolar search starts from the prediction and only
  // refines it. `converged` marks the point ready for activation at once (the
  // first keyframe of a map, which has nothing to trace against).
  void SetPredictedInterval(float idepth, float relative_range, bool converged);

  bool HasFiniteInterval() const { return std::isfinite(idepth_max) && idepth_max > 0; }
  float IdepthEstimate() const { return 0.5f * (idepth_min + idepth_max); }
  bool ReadyForActivation(const ImmaturePointOptions& options) const;

  // Epipolar search in `target`. `KRKi` and `Kt` relate host to target pixels:
  // p_target ~ KRKi * (u, v, 1) + Kt * idepth (level 0). (a, b): affine
  // transfer host -> target, I_target ~ a * I_host + b. `max_search_px` > 0
  // overrides the search length for unbounded intervals (static stereo).
  TraceStatus Trace(const PyramidLevel& target, const Eigen::Matrix3f& KRKi, const Eigen::Vector3f& Kt, float a,
                    float b, const ImmaturePointOptions& options, float max_search_px = -1.0f);
};

}  // namespace dvso::vo
