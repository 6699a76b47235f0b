// Shared by `dvso ablation` and `dvso tune-baseline`: runs one odometry
// variant over a sequence with ground truth and measures it with the KITTI
// protocol (unaligned t_rel / r_rel for the metric modes, Sim(3) for mono).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/disparity_source.h"
#include "core/sequence.h"
#include "core/trajectory.h"
#include "pipelines/prediction_source.h"
#include "vo/system/odometry_options.h"

namespace dvso::cli {

struct VariantResult {
  std::string name;
  double t_rel = 0;         // percent; unaligned (Sim(3)-aligned for mono)
  double r_rel = 0;         // deg / 100 m; same alignment as t_rel
  double sim3_scale = 0;    // scale of the Sim(3) alignment estimate -> GT (1 = metric)
  double ate_rmse = 0;      // metres; unaligned (Sim(3)-aligned for mono)
  double ms_per_frame = 0;  // odometry time per frame (excl. image reading)
  int lost = 0;
  int resets = 0;
  bool aligned = false;     // metrics after Sim(3) alignment (mono)
  int segments = 0;         // KITTI segments evaluated (0: path shorter than 100 m, t_rel / r_rel undefined)
  // t_rel / r_rel are null when segments == 0 (undefined, not zero).
  nlohmann::json ToJson() const;
};

// What tune-baseline minimises. One metric for the whole search, so that the mean over several
// sequences never adds percent to metres: t_rel when the GT path of every sequence (over the
// evaluated frames) is long enough for a KITTI segment (100 m), else the ATE on every sequence.
enum class TuningMetric { kTRel, kAte };
// "t_rel_percent" | "ate_m": the JSON value of `error_metric`.
const char* TuningMetricName(TuningMetric metric);
// One line for the printed output: the metric, its unit and why it was chosen.
std::string DescribeTuningMetric(TuningMetric metric);
// A run's error in `metric`; +inf for t_rel when the run evaluated no segment (estimate poses missing).
double TuningError(const VariantResult& run, TuningMetric metric);

// Runs `mode` with `options` over the first `count` frames (-1 = all) of
// `sequence`, writing the usual outputs into out_dir, and evaluates against
// gt (one pose per sequence frame, KITTI order).
VariantResult RunVariant(const std::string& name, const SequenceReader& sequence, const Trajectory& gt,
                         vo::OdometryMode mode, const vo::OdometryOptions& options, DisparitySource* predictions,
                         int count, const std::string& out_dir);

// The prediction schedule of `ablation` and `tune-baseline` unless a config file or
// --prediction-schedule says otherwise: their rows are compared with each other, and
// keyframe-async results vary by ~1.5 points t_rel between identical runs (the prediction's
// arrival depends on load; docs/dvso.md), keyframe-blocking is deterministic.
inline constexpr const char* kExperimentPredictionTiming = "keyframe-blocking";

// Options both experiment commands take.
struct ExperimentArgs {
  std::vector<std::string> sequences, gts;  // --sequence / --gt pairs, in order; `ablation` takes one
  std::string out, config, preset = "default", camera_file, cameras = "grey";
  int count = -1;
  bool json = false;
  PredictionSourceArgs predictions;
};
// many_sequences: --sequence/--gt may be repeated (tune-baseline: the paper tunes b_v on
// its training sequences, not on one).
void AddExperimentOptions(CLI::App* cmd, ExperimentArgs* args, bool many_sequences);

struct ExperimentSequence {
  std::string path;
  std::unique_ptr<SequenceReader> reader;
  Trajectory gt;  // at least one pose per evaluated frame
};

// What the experiments share once opened: sequences with GT, base options, predictions.
struct ExperimentSetup {
  std::vector<ExperimentSequence> sequences;  // >= 1; several share one camera (f_x and width), so one b_v fits all
  vo::OdometryOptions options;   // preset + config; dvso.virtual_baseline = the default b_v
  PredictionSource predictions;  // opened for the first sequence
  // b_v of the rows without tb (and the centre of a default tune grid), the precedence of `dvso odometry`:
  // --virtual-baseline, else the config file's dvso.virtual_baseline, else the model's untuned one.
  double default_virtual_baseline = 0;
  const SequenceReader& first() const { return *sequences.front().reader; }
};
ExperimentSetup OpenExperiment(const ExperimentArgs& args);

// Grid search of the virtual baseline (paper "tb"): full DVSO (in+vs+lr) per
// value on every sequence of the setup.
struct BaselineSearch {
  std::vector<VariantResult> runs;  // value-major: runs[v * sequences + s]
  std::vector<double> values;
  TuningMetric metric = TuningMetric::kAte;  // the one error every run is scored by (TuningMetric)
  std::vector<double> mean_error;   // per value: mean TuningError over the sequences (inf if any run lost tracking)
  double best = 0;                  // the value with the lowest mean_error
};
// Out_dir gets one folder per run (bv_<label>, or bv_<label>_<k> with several sequences; label:
// BaselineRunLabel). Throws before any run when two values share a label.
BaselineSearch TuneVirtualBaseline(const ExperimentSetup& setup, const std::vector<double>& values, int count,
                                   const std::string& out_dir, bool progress);

// b_v as run names and folders show it: %g with enough significant digits to keep the values of
// any sensible grid apart (0.5 and 0.5004), few enough that a grid's rounding (0.5004000000000001)
// reads as typed.
std::string BaselineRunLabel(double virtual_baseline);

// "start:step:end" (inclusive) -> values; throws dvso::Error naming `option` (e.g. "--values") on bad text.
std::vector<double> ParseRange(const std::string& text, const std::string& option);

// The b_v grid of a search: ParseRange(text, option), or without text nine values
// +-20 % (steps of 5 %) around `default_baseline`. Throws when two values would share a run label.
std::vector<double> BaselineGrid(const std::string& text, double default_baseline, const std::string& option);

// Table of results in the paper's Table 3 layout; t_rel / r_rel read "-" for a row without KITTI segments.
std::string FormatVariantTable(const std::vector<VariantResult>& results);

}  // namespace dvso::cli
