// YAML (de)serialisation of OdometryOptions. One visitor lists every field once,
// so load, save and print can never disagree about the keys.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <type_traits>
#include <sstream>
#include <yaml-cpp/yaml.h>

#include "core/config_yaml.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "vo/system/odometry_options.h"

namespace dvso::vo {

namespace {

// Calls v(section, key, field) for every field.
template <typename Options, typename Visitor>
void VisitFields(Options& o, Visitor&& v) {
  v("", "active_points", o.active_points);
  v("", "optimization_iterations", o.optimization_iterations);
  v("", "bundle_adjustment", o.bundle_adjustment);
  v("", "stereo_max_disparity_fraction", o.stereo_max_disparity_fraction);
  v("", "stereo_max_disparity_px", o.stereo_max_disparity_px);
  v("", "min_activation_distance", o.min_activation_distance);
  v("", "reinitialize_on_loss", o.reinitialize_on_loss);
  v("", "max_consecutive_lost", o.max_consecutive_lost);
  v("", "gamma_file", o.gamma_file);
  v("", "vignette_file", o.vignette_file);
  v("", "right_vignette_file", o.right_vignette_file);

  v("pyramid", "max_levels", o.pyramid.max_levels);
  v("pyramid", "min_top_level_pixels", o.pyramid.min_top_level_pixels);
  v("pyramid", "min_level_side", o.pyramid.min_level_side);

  v("stereo_brightness", "estimate", o.stereo_brightness.estimate);
  v("stereo_brightness", "sample_step", o.stereo_brightness.sample_step);
  v("stereo_brightness", "border_fraction", o.stereo_brightness.border_fraction);
  v("stereo_brightness", "min_quantile", o.stereo_brightness.min_quantile);
  v("stereo_brightness", "max_quantile", o.stereo_brightness.max_quantile);
  v("stereo_brightness", "num_quantiles", o.stereo_brightness.num_quantiles);
  v("stereo_brightness", "huber_threshold", o.stereo_brightness.huber_threshold);
  v("stereo_brightness", "max_gain_ratio", o.stereo_brightness.max_gain_ratio);
  v("stereo_brightness", "min_matched_points", o.stereo_brightness.min_matched_points);
  v("stereo_brightness", "max_matching_passes", o.stereo_brightness.max_matching_passes);
  v("stereo_brightness", "rematch_change", o.stereo_brightness.rematch_change);
  v("stereo_brightness", "estimate_radial", o.stereo_brightness.estimate_radial);
  v("stereo_brightness", "max_radial", o.stereo_brightness.max_radial);
  v("stereo_brightness", "radial_pool_keyframes", o.stereo_brightness.radial_pool_keyframes);

  v("selector", "desired_points", o.selector.desired_points);
  v("selector", "region_size", o.selector.region_size);
  v("selector", "min_grad_hist_cut", o.selector.min_grad_hist_cut);
  v("selector", "min_grad_hist_add", o.selector.min_grad_hist_add);
  v("selector", "grad_downweight_per_level", o.selector.grad_downweight_per_level);
  v("selector", "border", o.selector.border);
  v("selector", "max_adapt_iterations", o.selector.max_adapt_iterations);
  v("selector", "seed", o.selector.seed);

  v("tracker", "huber_threshold", o.tracker.huber_threshold);
  v("tracker", "cutoff_threshold", o.tracker.cutoff_threshold);
  v("tracker", "gradient_weight_c", o.tracker.gradient_weight_c);
  v("tracker", "max_iterations_finest", o.tracker.max_iterations_finest);
  v("tracker", "max_iterations_coarse", o.tracker.max_iterations_coarse);
  v("tracker", "initial_lambda", o.tracker.initial_lambda);
  v("tracker", "convergence_eps", o.tracker.convergence_eps);
  v("tracker", "max_affine_a", o.tracker.max_affine_a);
  v("tracker", "min_inlier_fraction", o.tracker.min_inlier_fraction);
  v("tracker", "min_points", o.tracker.min_points);
  v("tracker", "retrack_ratio", o.tracker.retrack_ratio);
  v("tracker", "estimate_affine", o.tracker.estimate_affine);

  v("immature", "huber_threshold", o.immature.huber_threshold);
  v("immature", "outlier_energy_per_pixel", o.immature.outlier_energy_per_pixel);
  v("immature", "extra_slack_on_threshold", o.immature.extra_slack_on_threshold);
  v("immature", "max_search_fraction", o.immature.max_search_fraction);
  v("immature", "step_size", o.immature.step_size);
  v("immature", "slack_interval", o.immature.slack_interval);
  v("immature", "min_improvement_factor", o.immature.min_improvement_factor);
  v("immature", "gn_iterations", o.immature.gn_iterations);
  v("immature", "gn_threshold", o.immature.gn_threshold);
  v("immature", "min_test_radius", o.immature.min_test_radius);
  v("immature", "min_quality", o.immature.min_quality);
  v("immature", "max_pixel_interval", o.immature.max_pixel_interval);

  v("keyframe", "global_weight", o.keyframe.global_weight);
  v("keyframe", "max_shift_weight_t", o.keyframe.max_shift_weight_t);
  v("keyframe", "max_shift_weight_rt", o.keyframe.max_shift_weight_rt);
  v("keyframe", "max_affine_weight", o.keyframe.max_affine_weight);
  v("keyframe", "rmse_growth_factor", o.keyframe.rmse_growth_factor);
  v("keyframe", "max_frames_between", o.keyframe.max_frames_between);

  v("mono_init", "min_frames", o.mono_init.min_frames);
  v("mono_init", "max_frames", o.mono_init.max_frames);
  v("mono_init", "min_parallax_px", o.mono_init.min_parallax_px);
  v("mono_init", "regularization", o.mono_init.regularization);
  v("mono_init", "iterations_per_level", o.mono_init.iterations_per_level);
  v("mono_init", "translation_prior", o.mono_init.translation_prior);

  v("window", "max_keyframes", o.window.max_keyframes);
  v("window", "huber_threshold", o.window.huber_threshold);
  v("window", "outlier_energy_threshold", o.window.outlier_energy_threshold);
  v("window", "gradient_weight_c", o.window.gradient_weight_c);
  v("window", "image_border", o.window.image_border);
  v("window", "use_static_stereo", o.window.use_static_stereo);
  v("window", "static_stereo_weight", o.window.static_stereo_weight);
  v("window", "use_virtual_stereo", o.window.use_virtual_stereo);
  v("window", "virtual_stereo_weight", o.window.virtual_stereo_weight);
  v("window", "first_pose_prior", o.window.first_pose_prior);
  v("window", "affine_a_prior", o.window.affine_a_prior);
  v("window", "affine_b_prior", o.window.affine_b_prior);
  v("window", "first_estimate_jacobians", o.window.first_estimate_jacobians);
  v("window", "initial_lambda", o.window.initial_lambda);
  v("window", "min_idepth", o.window.min_idepth);
  v("window", "convergence_step", o.window.convergence_step);
  v("window", "min_relative_decrease", o.window.min_relative_decrease);
  v("window", "min_residuals_to_marginalize", o.window.min_residuals_to_marginalize);
  v("window", "max_log_affine_in_window", o.window.max_log_affine_in_window);
  v("window", "min_keyframes_kept", o.window.min_keyframes_kept);
  v("window", "num_threads", o.window.num_threads);

  v("dvso", "virtual_baseline", o.dvso.virtual_baseline);
  v("dvso", "left_right_check", o.dvso.left_right_check);
  v("dvso", "left_right_threshold", o.dvso.left_right_threshold);
  v("dvso", "init_relative_range", o.dvso.init_relative_range);
  v("dvso", "prediction_timing", o.dvso.prediction_timing);
}

OdometryOptions FromSection(YamlSection& root, const OdometryOptions& base) {
  OdometryOptions o = base;
  std::map<std::string, YamlSection*> children;  // one child per section, so its used keys accumulate
  VisitFields(o, [&root, &children](const char* section, const char* key, auto& field) {
    YamlSection* s = &root;
    if (section[0] != '\0') {
      auto it = children.find(section);
      if (it == children.end()) it = children.emplace(section, &root.Child(section)).first;
      s = it->second;
    }
    s->Read(key, &field);
  });
  // window.virtual_stereo_baseline was listed here once but System always sets it from dvso.virtual_baseline
  // (one b_v for the depth initialisation and eq. 5.8): an old config that names it gets told where b_v lives.
  if (const auto window = children.find("window");
      window != children.end() && window->second->Has("virtual_stereo_baseline")) {
    throw Error(root.origin(), "window.virtual_stereo_baseline is not a setting: the virtual baseline b_v is "
                               "dvso.virtual_baseline (0 = the model's); delete the line");
  }
  // immature.max_steps capped every discrete epipolar search at 100 samples, silently: removed, a search
  // covers its whole segment, and the static stereo limit is the explicit stereo_max_disparity_px.
  if (const auto immature = children.find("immature");
      immature != children.end() && immature->second->Has("max_steps")) {
    throw Error(root.origin(), "immature.max_steps is no longer a setting (it cut every epipolar search at 100 "
                               "samples; the static stereo search is now limited by stereo_max_disparity_px, "
                               "default 100): delete the line");
  }
  root.RequireAllKeysUsed();
  try {
    o.Check();
  } catch (const Error& e) {
    throw Error(root.origin(), e.what());
  }
  return o;
}

}  // namespace

OdometryOptions LoadOdometryOptions(const std::string& path, const OdometryOptions& base) {
  YamlSection root = YamlSection::FromFile(path);
  return FromSection(root, base);
}

OdometryOptions OdometryOptionsFromYamlString(const std::string& text, const OdometryOptions& base) {
  YamlSection root = YamlSection::FromString(text);
  return FromSection(root, base);
}

std::string OdometryOptionsToYaml(const OdometryOptions& options) {
  YAML::Node root;
  OdometryOptions copy = options;
  VisitFields(copy, [&root](const char* section, const char* key, auto& field) {
    YAML::Node node = section[0] == '\0' ? root[key] : root[section][key];
    using T = std::decay_t<decltype(field)>;
    if constexpr (std::is_same_v<T, double>) {
      // YAML's spelling of the non-finite values (yaml-cpp reads ".inf", not printf's "inf").
      if (!std::isfinite(field)) {
        node = std::isnan(field) ? std::string(".nan") : std::string(field > 0 ? ".inf" : "-.inf");
        return;
      }
      // Shortest text that reads back exactly ("0.2", not "0.20000000000000001").
      char text[64];
      for (int digits = 6; digits <= 17; ++digits) {
        std::snprintf(text, sizeof(text), "%.*g", digits, field);
        if (std::strtod(text, nullptr) == field) break;
      }
      node = std::string(text);
    } else {
      node = field;
    }
  });
  YAML::Emitter out;
  out << root;
  return std::string(out.c_str()) + "\n";
}

void SaveOdometryOptions(const std::string& path, const OdometryOptions& options) {
  const std::string text = OdometryOptionsToYaml(options);
  WriteStreamAtomically(path, [&text](std::ostream& out) { out << text; });
}

}  // namespace dvso::vo
