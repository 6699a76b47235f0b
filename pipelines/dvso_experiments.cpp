#include "pipelines/dvso_experiments.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/eval_odometry.h"
#include "core/fs_util.h"
#include "core/progress.h"
#include "vo/system/sequence_runner.h"

namespace dvso::cli {

namespace {

// b_v labels (BaselineRunLabel): 6 digits tell values 1 micrometre apart at 0.5 m, finer than any
// b_v a grid search can resolve, yet print a grid's 0.5004000000000001 as 0.5004.
constexpr int kRunLabelSignificantDigits = 6;

// Throws when two values of a grid would get one run name (and one folder: the second run would
// overwrite the first).
void RequireDistinctRunLabels(const std::vector<double>& values, const std::string& grid) {
  std::map<std::string, double> value_of_label;
  for (const double value : values) {
    const std::string label = BaselineRunLabel(value);
    const auto [earlier, inserted] = value_of_label.emplace(label, value);
    if (inserted) continue;
    std::ostringstream both;
    both << std::setprecision(std::numeric_limits<double>::max_digits10) << earlier->second << " and " << value;
    throw Error(grid + ": b_v " + both.str() + " share the run name " + label + " (" +
                std::to_string(kRunLabelSignificantDigits) + " significant digits): use a coarser step");
  }
}

// TuningMetric: t_rel only when every sequence's GT over the evaluated frames holds a KITTI segment
// (this depends on the GT path alone, not on b_v, so it is decided once before the runs).
TuningMetric ChooseTuningMetric(const ExperimentSetup& setup, int count) {
  for (const ExperimentSequence& s : setup.sequences) {
    const int frames = count < 0 ? s.reader->size() : std::min(count, s.reader->size());
    std::vector<Eigen::Isometry3d> path;
    for (int i = 0; i < frames && i < static_cast<int>(s.gt.size()); ++i) path.push_back(s.gt.poses[i].T_world_camera);
    // The GT against itself: the segments the evaluation would find with every estimated pose present.
    OdometryMetrics metrics;
    ComputeKittiSegmentErrors(path, path, std::vector<bool>(path.size(), true), OdometryEvalOptions{}, &metrics);
    if (metrics.segments == 0) return TuningMetric::kAte;
  }
  return TuningMetric::kTRel;
}

}  // namespace

nlohmann::json VariantResult::ToJson() const {
  // Without segments t_rel / r_rel are undefined: null, not a misleading 0.
  const nlohmann::json t_rel_json = segments > 0 ? nlohmann::json(t_rel) : nlohmann::json(nullptr);
  const nlohmann::json r_rel_json = segments > 0 ? nlohmann::json(r_rel) : nlohmann::json(nullptr);
  return {{"name", name},           {"t_rel", t_rel_json},   {"r_rel", r_rel_json}, {"sim3_scale", sim3_scale},
          {"ate_rmse", ate_rmse},   {"ms_per_frame", ms_per_frame},                 {"lost", lost},
          {"resets", resets},       {"aligned", aligned},    {"segments", segments}};
}

const char* TuningMetricName(TuningMetric metric) {
  return metric == TuningMetric::kTRel ? "t_rel_percent" : "ate_m";
}

std::string DescribeTuningMetric(TuningMetric metric) {
  return metric == TuningMetric::kTRel
             ? "error minimised: t_rel % (every sequence has KITTI segments)"
             : "error minimised: ATE m on every sequence (a GT path is shorter than a 100 m KITTI segment)";
}

double TuningError(const VariantResult& run, TuningMetric metric) {
  if (metric == TuningMetric::kAte) return run.ate_rmse;
  return run.segments > 0 ? run.t_rel : std::numeric_limits<double>::infinity();
}

std::string BaselineRunLabel(double virtual_baseline) {
  std::ostringstream label;
  label << std::setprecision(kRunLabelSignificantDigits) << virtual_baseline;
  return label.str();
}

VariantResult RunVariant(const std::string& name, const SequenceReader& sequence, const Trajectory& gt,
                         vo::OdometryMode mode, const vo::OdometryOptions& options, DisparitySource* predictions,
                         int count, const std::string& out_dir) {
  vo::SequenceRunOptions run;
  run.count = count;
  run.progress = false;
  run.predictions = predictions;
  const vo::SequenceRunSummary summary = vo::RunOdometryOnSequence(sequence, options, mode, out_dir, run);
  const Trajectory estimate = ReadTrajectory(JoinPath(out_dir, "trajectory.txt"), TrajectoryFormat::kKitti);
  Trajectory truth;
  truth.poses.assign(gt.poses.begin(), gt.poses.begin() + std::min(gt.size(), estimate.size()));
  VariantResult r;
  r.name = name;
  r.aligned = CapabilitiesOf(mode).needs_mono_initializer;
  OdometryEvalOptions eval;
  eval.align = AlignmentMode::kSim3;
  const OdometryMetrics sim3 = EvaluateOdometry(truth, estimate, eval);
  r.sim3_scale = sim3.alignment.scale;
  eval.align = r.aligned ? AlignmentMode::kSim3 : AlignmentMode::kNone;
  const OdometryMetrics m = r.aligned ? sim3 : EvaluateOdometry(truth, estimate, eval);
  r.segments = m.segments;
  r.t_rel = m.segments > 0 ? m.t_rel : 0.0;
  r.r_rel = m.segments > 0 ? m.r_rel : 0.0;
  r.ate_rmse = m.ate_rmse;
  r.ms_per_frame = summary.mean_ms;
  r.lost = summary.lost;
  r.resets = summary.resets;
  return r;
}

void AddExperimentOptions(CLI::App* cmd, ExperimentArgs* args, bool many_sequences) {
  const std::string repeat = many_sequences ? " (repeatable: one --gt per --sequence, in order)" : "";
  auto* sequence = cmd->add_option("--sequence", args->sequences,
                                   "Sequence (KITTI layout, EuRoC, or image folder + --camera)" + repeat)
                       ->required();
  auto* gt = cmd->add_option("--gt", args->gts, "Ground-truth poses, one KITTI line per sequence frame" + repeat)
                 ->required()
                 ->check(CLI::ExistingFile);
  if (!many_sequences) {
    sequence->expected(1);
    gt->expected(1);
  }
  cmd->add_option("--out", args->out, "Folder for the runs' outputs (one subfolder per run)")->required();
  cmd->add_option("--count", args->count, "Frames from the start of each sequence (-1 = all)");
  cmd->add_option("--config", args->config, "Odometry YAML options (strict keys)");
  cmd->add_option("--preset", args->preset, "default | fast")->check(CLI::IsMember({"default", "fast"}));
  cmd->add_option("--camera", args->camera_file, "DSO camera file (image-folder sequences only)");
  cmd->add_option("--cameras", args->cameras, "KITTI layouts (raw drive, odometry folder): grey (00/01) or colour (02/03, read as grey) pair")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print exactly one JSON object on stdout");
  AddPredictionOptions(cmd, &args->predictions, kExperimentPredictionTiming);
}

ExperimentSetup OpenExperiment(const ExperimentArgs& args) {
  Require(!args.sequences.empty() && args.sequences.size() == args.gts.size(),
          "give one --gt per --sequence (" + std::to_string(args.sequences.size()) + " sequences, " +
              std::to_string(args.gts.size()) + " --gt)");
  Require(args.sequences.size() == 1 || args.predictions.disparity_left.empty(),
          "disparity files belong to one sequence: several --sequence need --model (or the shipped model)");
  ExperimentSetup setup;
  setup.options = vo::OdometryOptions::Preset(args.preset);
  // Under the config file and the flag, so either still decides.
  setup.options.dvso.prediction_timing = kExperimentPredictionTiming;
  if (!args.config.empty()) setup.options = vo::LoadOdometryOptions(args.config, setup.options);
  for (size_t i = 0; i < args.sequences.size(); ++i) {
    ExperimentSequence s;
    s.path = args.sequences[i];
    s.reader = OpenSequence(s.path, args.camera_file, ParseCameraPair(args.cameras));
    s.gt = ReadTrajectory(args.gts[i], TrajectoryFormat::kKitti);
    const int frames = args.count < 0 ? s.reader->size() : std::min(args.count, s.reader->size());
    RequireFile(static_cast<int>(s.gt.size()) >= frames, args.gts[i],
                "has " + std::to_string(s.gt.size()) + " poses for " + std::to_string(frames) + " frames");
    if (!setup.sequences.empty() && !args.predictions.disparity_left.empty()) {
      // Disparity files are in their own sequence's stereo geometry: one b_v grid needs one camera. (A
      // model's b_v is the same for every camera: core/disparity_conversion.h.)
      const PinholeCamera& a = setup.first().camera().left;
      const PinholeCamera& b = s.reader->camera().left;
      RequireFile(std::abs(a.fx - b.fx) < 1e-6 * a.fx && a.width == b.width, s.path,
                  "has another camera (f_x, width) than " + setup.sequences.front().path +
                      ": one b_v grid needs one camera");
    }
    setup.sequences.push_back(std::move(s));
  }
  const double config_virtual_baseline = setup.options.dvso.virtual_baseline;  // > 0 only when a config set it
  setup.predictions = OpenPredictionSource(args.predictions, setup.first());
  ApplyPredictionSource(args.predictions, &setup.predictions, &setup.options);
  setup.default_virtual_baseline = config_virtual_baseline > 0 && !(args.predictions.virtual_baseline > 0)
                                       ? config_virtual_baseline
                                       : setup.predictions.untuned_virtual_baseline;
  return setup;
}

BaselineSearch TuneVirtualBaseline(const ExperimentSetup& setup, const std::vector<double>& values, int count,
                                   const std::string& out_dir, bool progress) {
  RequireDistinctRunLabels(values, "the b_v grid");
  BaselineSearch search;
  search.values = values;
  search.metric = ChooseTuningMetric(setup, count);
  const size_t n = setup.sequences.size();
  std::unique_ptr<ProgressBar> bar;
  if (progress) bar = std::make_unique<ProgressBar>("tune-baseline", static_cast<long>(values.size() * n));
  double best_error = std::numeric_limits<double>::infinity();
  for (const double b : values) {
    vo::OdometryOptions options = setup.options;
    options.dvso.virtual_baseline = b;
    const std::string label = BaselineRunLabel(b);
    double sum = 0;
    bool lost = false;
    for (size_t k = 0; k < n; ++k) {
      const ExperimentSequence& s = setup.sequences[k];
      const std::string run_name = "b_v=" + label + (n > 1 ? " #" + std::to_string(k + 1) : "");
      const std::string dir = JoinPath(out_dir, "bv_" + label + (n > 1 ? "_" + std::to_string(k + 1) : ""));
      search.runs.push_back(RunVariant(run_name, *s.reader, s.gt, vo::OdometryMode::kDvso, options,
                                       setup.predictions.source.get(), count, dir));
      sum += TuningError(search.runs.back(), search.metric);
      lost = lost || search.runs.back().lost > 0;
      if (bar) bar->Update(static_cast<long>(search.runs.size()), run_name);
    }
    // A value that loses tracking anywhere is not a candidate.
    search.mean_error.push_back(lost ? std::numeric_limits<double>::infinity() : sum / static_cast<double>(n));
    if (search.mean_error.back() < best_error) {
      best_error = search.mean_error.back();
      search.best = b;
    }
  }
  if (bar) bar->Finish();
  Require(std::isfinite(best_error), "tune-baseline: every value lost tracking on some sequence");
  return search;
}

std::vector<double> ParseRange(const std::string& text, const std::string& option) {
  std::vector<double> parts;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ':');) {
    try {
      size_t used = 0;
      parts.push_back(std::stod(item, &used));
      Require(used == item.size(), "");
    } catch (const std::exception&) {
      throw Error(option + " '" + text + "': expected start:step:end (metres), e.g. 0.3:0.05:0.8");
    }
  }
  Require(parts.size() == 3 && parts[1] > 0 && parts[0] > 0 && parts[2] >= parts[0],
          option + " '" + text + "': expected start:step:end with 0 < start <= end and step > 0");
  std::vector<double> values;
  // Each value is a whole odometry run: a grid of more than this is a typo (e.g. a step of 1e-9), not a plan.
  constexpr double kMaxGridValues = 200;
  const double count = std::floor((parts[2] - parts[0]) / parts[1] + 1e-9) + 1;
  Require(count <= kMaxGridValues, option + " '" + text + "': " + std::to_string(static_cast<long long>(count)) +
                                       " values, more than the " + std::to_string(static_cast<int>(kMaxGridValues)) +
                                       " odometry runs a grid search may take");
  const int n = static_cast<int>(count);
  // start + i * step carries binary rounding (0.3 + 5 * 0.05 = 0.5599999999999999), which JSON and
  // the tuned model's metadata would print in full: snap to a nanometre, far below any baseline step.
  // (Dividing the integer count of nanometres by 1e9, both exact, gives the double nearest the decimal.)
  constexpr double kNanometresPerMetre = 1e9;
  for (int i = 0; i < n; ++i) {
    values.push_back(std::round((parts[0] + i * parts[1]) * kNanometresPerMetre) / kNanometresPerMetre);
  }
  return values;
}

std::vector<double> BaselineGrid(const std::string& text, double default_baseline, const std::string& option) {
  std::vector<double> grid;
  if (!text.empty()) {
    grid = ParseRange(text, option);
  } else {
    constexpr int kStepsEachSide = 4;  // +-20 %
    constexpr double kRelativeStep = 0.05;
    for (int k = -kStepsEachSide; k <= kStepsEachSide; ++k) grid.push_back(default_baseline * (1.0 + kRelativeStep * k));
  }
  RequireDistinctRunLabels(grid, text.empty() ? "the default " + option + " grid" : option + " '" + text + "'");
  return grid;
}

std::string FormatVariantTable(const std::vector<VariantResult>& results) {
  std::ostringstream out;
  out << std::left << std::setw(14) << "variant" << std::right << std::setw(10) << "t_rel %" << std::setw(16)
      << "r_rel deg/100m" << std::setw(12) << "Sim3 scale" << std::setw(11) << "ATE m" << std::setw(11)
      << "ms/frame" << std::setw(6) << "lost" << "\n";
  out << std::fixed;
  bool any_without_segments = false;
  for (const VariantResult& r : results) {
    out << std::left << std::setw(14) << (r.name + (r.aligned ? "*" : "")) << std::right << std::setprecision(3);
    // t_rel / r_rel are undefined without a KITTI segment: a 0.000 there would read as a perfect run.
    if (r.segments > 0) {
      out << std::setw(10) << r.t_rel << std::setw(16) << r.r_rel;
    } else {
      out << std::setw(10) << "-" << std::setw(16) << "-";
      any_without_segments = true;
    }
    out << std::setprecision(4) << std::setw(12) << r.sim3_scale << std::setprecision(3) << std::setw(11)
        << r.ate_rmse << std::setprecision(1) << std::setw(11) << r.ms_per_frame << std::setw(6) << r.lost << "\n";
  }
  out << "(* after Sim(3) alignment; every other row is unaligned, KITTI protocol)\n";
  if (any_without_segments) out << "(- : the GT path is shorter than a 100 m KITTI segment)\n";
  return out.str();
}

}  // namespace dvso::cli
