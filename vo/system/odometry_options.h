// All options of the odometry System in one struct, with DSO's defaults
// (Engel et al. 2017; Stereo DSO, Wang et al. 2017). Loaded from YAML with
// strict keys (odometry_options_yaml.cpp); presets "default" and "fast".
#pragma once

#include <string>

#include "vo/frame/image_pyramid.h"
#include "vo/frame/stereo_brightness.h"
#include "vo/frontend/coarse_tracker.h"
#include "vo/frontend/immature_point.h"
#include "vo/frontend/keyframe_decision.h"
#include "vo/frontend/mono_initializer.h"
#include "vo/frontend/pixel_selector.h"
#include "vo/optimization/window.h"

namespace dvso::vo {

enum class OdometryMode {
  kMono,    // DSO: left images only, scale from the monocular initialiser (arbitrary)
  kStereo,  // Stereo DSO: left + right images, static stereo residuals, metric
  kDvso,    // DVSO (paper section 4): left images + predicted D^L / D^R, metric
};

OdometryMode ParseOdometryMode(const std::string& text);  // "mono" | "stereo" | "dvso"; throws dvso::Error
std::string ToString(OdometryMode mode);

// What a mode brings; the System asks these instead of comparing mode names.
struct ModeCapabilities {
  bool has_right_image = false;         // static stereo matching of candidates and static stereo residuals
  bool has_predictions = false;         // depth init from D^L, left-right check, virtual stereo with D^R
  bool needs_mono_initializer = false;  // no metric depth at the first frame: two-frame monocular start
  bool StartsMetric() const { return !needs_mono_initializer; }
};
ModeCapabilities CapabilitiesOf(OdometryMode mode);

// When a keyframe's prediction is computed (DVSO with a source that has a worker).
enum class PredictionTiming {
  kKeyframeAsync,     // requested when the frame becomes a keyframe; attached (D^R, candidates) when it arrives,
                      // while the next frames are tracked: inference overlaps the odometry
  kKeyframeBlocking,  // requested and waited for when the frame becomes a keyframe
  kSpeculative,       // every frame is requested while it is tracked; a keyframe waits for its own
};
PredictionTiming ParsePredictionTiming(const std::string& text);  // "keyframe-async" | "keyframe-blocking" | "speculative"
std::string ToString(PredictionTiming timing);

// DVSO-specific options (paper section 4). The virtual stereo term itself is
// configured in WindowOptions (use_virtual_stereo, virtual_stereo_weight =
// lambda); its baseline is set from virtual_baseline below.
struct DvsoOptions {
  double virtual_baseline = 0.0;       // b_v (metres) in d = D / (f_x b_v); 0 = from the model / disparity source
  bool left_right_check = true;        // paper "lr": pixels with e_lr > threshold are not selected
  double left_right_threshold = 1.0;   // e_lr threshold (pixels, paper: 1)
  double init_relative_range = 0.25;   // candidates search the inverse depth in d_pred * [1 - r, 1 + r] (epipolar refinement)
  std::string prediction_timing = "keyframe-async";  // keyframe-async | keyframe-blocking | speculative (PredictionTiming)
  void Check() const;
};

struct OdometryOptions {
  int active_points = 2000;           // desired active points in the window (DSO setting_desiredPointDensity)
  int optimization_iterations = 6;    // LM iterations per keyframe (DSO setting_maxOptIterations)
  bool bundle_adjustment = true;      // run the windowed optimisation (off: poses from tracking only, for diagnosis)
  double stereo_max_disparity_fraction = 0.2;  // static stereo search length, fraction of the image width ...
  // ... and at most this many pixels. Until session 23 DSO's cap of 100 search steps did this silently
  // (the 0.2 alone is 248 px at 1241); searching all 248 px cost 3-4 % of the labels on 4 of 5 issue-12
  // worlds and 0.85 points of accuracy on one (docs/labels.md, session 23): a longer search finds more
  // look-alike patches. Surfaces nearer than fx*b / 100 px (3.9 m on KITTI) are not matched.
  double stereo_max_disparity_px = 100.0;
  double min_activation_distance = 2.0;  // lower bound of the adaptive activation grid cell (pixels)
  bool reinitialize_on_loss = true;   // tracking failure -> start a new map (else the run stops)
  int max_consecutive_lost = 1000000; // give up (error) after this many consecutive lost frames
  std::string gamma_file;             // optional inverse response (DSO pcalib.txt), empty = none
  std::string vignette_file;          // optional vignette PNG, empty = none
  std::string right_vignette_file;    // stereo: the right lens's own vignette PNG, empty = vignette_file for both

  ImagePyramidOptions pyramid;
  StereoBrightnessOptions stereo_brightness;  // the right camera's brightness transfer (stereo mode)
  PixelSelectorOptions selector;      // candidate (immature) points per keyframe (DSO desiredImmatureDensity 1500)
  CoarseTrackerOptions tracker;
  ImmaturePointOptions immature;
  KeyframeDecisionOptions keyframe;
  MonoInitializerOptions mono_init;
  WindowOptions window;
  DvsoOptions dvso;

  OdometryOptions() {
    selector.desired_points = 1500;  // DSO setting_desiredImmatureDensity
    window.num_threads = 2;          // the target machine has 2 cores; tracking is idle while the window optimises
  }

  // Throws dvso::Error on any invalid value (checks every sub-struct).
  void Check() const;

  // Presets: "default" (DSO: 2000 active points, 1500 candidates per keyframe)
  // and "fast" (800 active points, 600 candidates, fewer iterations).
  static OdometryOptions Preset(const std::string& name);
};

// Strict YAML: every key must be known (unknown key = dvso::Error naming it).
// Keys absent from the file keep the values of `base`.
OdometryOptions LoadOdometryOptions(const std::string& path, const OdometryOptions& base = OdometryOptions{});
OdometryOptions OdometryOptionsFromYamlString(const std::string& text, const OdometryOptions& base = OdometryOptions{});
std::string OdometryOptionsToYaml(const OdometryOptions& options);
void SaveOdometryOptions(const std::string& path, const OdometryOptions& options);

}  // namespace dvso::vo
