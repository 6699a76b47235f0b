#include "vo/frontend/keyframe_decision.h"

#include <cmath>

#include "core/error.h"

namespace dvso::vo {

void KeyframeDecisionOptions::Check() const {
  Require(global_weight > 0, "keyframe global_weight must be > 0");
  Require(max_shift_weight_t >= 0 && max_shift_weight_rt >= 0 && max_affine_weight >= 0,
          "keyframe weights must be >= 0");
  Require(rmse_growth_factor > 1, "keyframe rmse_growth_factor must be > 1");
  Require(max_frames_between >= 0, "keyframe max_frames_between must be >= 0");
}

double KeyframeScore(const KeyframeDecisionInput& in, const KeyframeDecisionOptions& o) {
  Require(in.tracking != nullptr && in.image_width > 0 && in.image_height > 0, "KeyframeScore: invalid input");
  const double size = in.image_width + in.image_height;
  const TrackingResult& t = *in.tracking;
  return o.global_weight * (o.max_shift_weight_t * std::sqrt(t.flow_sq_t) / size +
                            o.max_shift_weight_rt * std::sqrt(t.flow_sq_rt) / size +
                            o.max_affine_weight * std::fabs(t.affine_a));
}

bool NeedKeyframe(const KeyframeDecisionInput& in, const KeyframeDecisionOptions& o) {
  if (o.max_frames_between > 0 && in.frames_since_keyframe >= o.max_frames_between) return true;
  if (KeyframeScore(in, o) > 1.0) return true;
  return in.first_rmse > 0 && in.tracking->rmse > o.rmse_growth_factor * in.first_rmse;
}

}  // namespace dvso::vo
