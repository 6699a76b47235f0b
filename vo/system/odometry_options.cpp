#include "vo/system/odometry_options.h"

#include "core/error.h"

namespace dvso::vo {

OdometryMode ParseOdometryMode(const std::string& text) {
  if (text == "mono") return OdometryMode::kMono;
  if (text == "stereo") return OdometryMode::kStereo;
  if (text == "dvso") return OdometryMode::kDvso;
  throw Error("unknown odometry mode '" + text + "' (expected mono, stereo or dvso)");
}

std::string ToString(OdometryMode mode) {
  switch (mode) {
    case OdometryMode::kMono: return "mono";
    case OdometryMode::kStereo: return "stereo";
    case OdometryMode::kDvso: return "dvso";
  }
  return "unknown";
}

ModeCapabilities CapabilitiesOf(OdometryMode mode) {
  ModeCapabilities c;
  c.has_right_image = mode == OdometryMode::kStereo;
  c.has_predictions = mode == OdometryMode::kDvso;
  c.needs_mono_initializer = mode == OdometryMode::kMono;
  return c;
}

PredictionTiming ParsePredictionTiming(const std::string& text) {
  if (text == "keyframe-async") return PredictionTiming::kKeyframeAsync;
  if (text == "keyframe-blocking") return PredictionTiming::kKeyframeBlocking;
  if (text == "speculative") return PredictionTiming::kSpeculative;
  throw Error("unknown prediction timing '" + text + "' (expected keyframe-async, keyframe-blocking or speculative)");
}

std::string ToString(PredictionTiming timing) {
  switch (timing) {
    case PredictionTiming::kKeyframeAsync: return "keyframe-async";
    case PredictionTiming::kKeyframeBlocking: return "keyframe-blocking";
    case PredictionTiming::kSpeculative: return "speculative";
  }
  return "unknown";
}

void DvsoOptions::Check() const {
  ParsePredictionTiming(prediction_timing);
  Require(virtual_baseline >= 0, "dvso virtual_baseline must be >= 0 (0 = from the model)");
  Require(left_right_threshold > 0, "dvso left_right_threshold must be > 0");
  Require(init_relative_range > 0 && init_relative_range < 1, "dvso init_relative_range must be in (0, 1)");
}

void OdometryOptions::Check() const {
  Require(active_points >= 10, "active_points must be >= 10");
  Require(optimization_iterations >= 0, "optimization_iterations must be >= 0");
  Require(stereo_max_disparity_fraction > 0 && stereo_max_disparity_fraction <= 1,
          "stereo_max_disparity_fraction must be in (0, 1]");
  Require(stereo_max_disparity_px >= 1, "stereo_max_disparity_px must be >= 1");
  Require(min_activation_distance >= 1, "min_activation_distance must be >= 1");
  Require(max_consecutive_lost >= 1, "max_consecutive_lost must be >= 1");
  pyramid.Check();
  stereo_brightness.Check();
  selector.Check();
  tracker.Check();
  immature.Check();
  keyframe.Check();
  mono_init.Check();
  window.Check();
  dvso.Check();
}

OdometryOptions OdometryOptions::Preset(const std::string& name) {
  OdometryOptions o;
  if (name == "default") return o;
  if (name == "fast") {
    o.active_points = 800;
    o.selector.desired_points = 600;
    o.optimization_iterations = 4;
    o.tracker.max_iterations_coarse = 20;
    return o;
  }
  throw Error("unknown odometry preset '" + name + "' (expected default or fast)");
}

}  // namespace dvso::vo
