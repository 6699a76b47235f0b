// DSO's keyframe criteria: a new keyframe is needed when the mean optical flow
// since the reference keyframe (translation-only flow and full flow, scaled by
// the image size) or the exposure/brightness change grows too large, or when
// the tracking residual doubled relative to the first frame tracked against
// the reference (DSO FullSystem::deliverTrackedFrame).
#pragma once

#include "vo/frontend/coarse_tracker.h"

namespace dvso::vo {

struct KeyframeDecisionOptions {
  double global_weight = 1.0;           // scales all flow/affine terms (DSO setting_kfGlobalWeight)
  double max_shift_weight_t = 44.8;     // translation-only flow weight, 0.04 * (640 + 480) (DSO setting_maxShiftWeightT)
  double max_shift_weight_rt = 22.4;    // full flow weight, 0.02 * (640 + 480) (DSO setting_maxShiftWeightRT)
  double max_affine_weight = 2.0;       // weight of |log brightness ratio| (DSO setting_maxAffineWeight)
  double rmse_growth_factor = 2.0;      // keyframe when rmse > factor * first rmse after the reference (DSO: 2)
  int max_frames_between = 0;           // force a keyframe after this many frames (0 = never force)
  void Check() const;
};

struct KeyframeDecisionInput {
  const TrackingResult* tracking = nullptr;  // result of the current frame against the reference
  int image_width = 0;
  int image_height = 0;
  double first_rmse = 0;        // rmse of the first frame tracked against the current reference (0 = unknown)
  int frames_since_keyframe = 0;
};

// Returns the DSO score (> 1 means "make a keyframe"); exposed for tests/logs.
double KeyframeScore(const KeyframeDecisionInput& input, const KeyframeDecisionOptions& options);
bool NeedKeyframe(const KeyframeDecisionInput& input, const KeyframeDecisionOptions& options);

}  // namespace dvso::vo
