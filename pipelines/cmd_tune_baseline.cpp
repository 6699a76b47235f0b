// `dvso tune-baseline`: the paper's grid search of the virtual stereo baseline
// ("tb") on one or more sequences with ground truth (the paper tunes on its
// training sequences): full DVSO per value and sequence, the value with the
// lowest mean error wins. The error is one metric for the whole search
// (TuningMetric): unaligned t_rel when every sequence's GT path holds a KITTI
// segment (100 m), else the ATE on every sequence, never a mix of the two.
#include <cmath>
#include <filesystem>
#include <iostream>

#include "core/error.h"
#include "pipelines/commands.h"
#include "pipelines/dvso_experiments.h"

namespace dvso::cli {

namespace {

// --write-model stamps the result into a copy of the model: what it needs is checked before the
// grid runs (hours on real sequences), not after. The checks that need no opened model.
void RequireWriteModelArguments(const ExperimentArgs& experiment, const std::string& write_model) {
  Require(experiment.predictions.disparity_left.empty() && experiment.predictions.disparity_right.empty(),
          "--write-model stamps b_v into a model: use --model (or the shipped model), not disparity files");
  const std::filesystem::path folder = std::filesystem::path(write_model).parent_path();
  RequireFile(folder.empty() || std::filesystem::is_directory(folder), write_model,
              "--write-model: the folder " + folder.string() + " does not exist");
}

// The model the search runs (OpenExperiment has opened it): --model, else the shipped one.
std::string ModelInUse(const ExperimentArgs& experiment) {
  return experiment.predictions.model.empty() ? ShippedModelPath() : experiment.predictions.model;
}

}  // namespace

void AddTuneBaselineCommand(CLI::App& app) {
  struct Args {
    ExperimentArgs experiment;
    std::string values;
    std::string write_model;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand(
      "tune-baseline",
      "Grid search of the DVSO virtual baseline b_v on one or more sequences with GT (lowest mean error wins: "
      "unaligned t_rel when every GT path has KITTI segments of 100 m, else the ATE on every sequence)");
  AddExperimentOptions(cmd, &args->experiment, /*many_sequences=*/true);
  cmd->add_option("--values", args->values, "start:step:end in metres (default: +-20 % around the model's b_v)");
  cmd->add_option("--write-model", args->write_model,
                  "Write a copy of the model (--model or the shipped one) carrying the best b_v (paper 'tb'); "
                  "dvso odometry then uses it");
  cmd->callback([args] {
    const ExperimentArgs& experiment = args->experiment;
    const bool write_model = !args->write_model.empty();
    if (write_model) RequireWriteModelArguments(experiment, args->write_model);
    const ExperimentSetup setup = OpenExperiment(experiment);
    const std::string model = ModelInUse(experiment);
    if (write_model) {
      // --virtual-baseline skips this check when the source is opened; the stamped b_v needs it.
      RequireFile(setup.predictions.metadata.has_camera(), model,
                  "carries no training camera (baseline, fx/width) to stamp the tuned b_v beside: --write-model "
                  "needs a model from `dvso export`");
    }
    const double default_bv = setup.default_virtual_baseline;
    const std::vector<double> grid = BaselineGrid(args->values, default_bv, "--values");
    const BaselineSearch search = TuneVirtualBaseline(setup, grid, experiment.count, experiment.out, !experiment.json);
    const size_t n = setup.sequences.size();
    if (write_model) {
      ModelMetadata metadata = setup.predictions.metadata;
      metadata.tuned_baseline = search.best;  // b_v is the same for every camera (core/disparity_conversion.h)
      std::string tuned_on;
      for (const ExperimentSequence& s : setup.sequences) tuned_on += (tuned_on.empty() ? "" : ", ") + s.path;
      if (experiment.count > 0) tuned_on += " (first " + std::to_string(experiment.count) + " frames of each)";
      metadata.tuned_on = tuned_on;
      WriteModelWithTunedBaseline(model, args->write_model, metadata);
      (experiment.json ? std::cerr : std::cout) << "wrote " << args->write_model << " (tuned baseline "
                                                << metadata.tuned_baseline << " m, used for every camera)\n";
    }
    if (experiment.json) {
      nlohmann::json j;
      j["default_virtual_baseline"] = default_bv;
      j["best_virtual_baseline"] = search.best;
      j["error_metric"] = TuningMetricName(search.metric);
      j["prediction_timing"] = setup.options.dvso.prediction_timing;
      for (const ExperimentSequence& s : setup.sequences) j["sequences"].push_back(s.path);
      for (size_t i = 0; i < search.runs.size(); ++i) {
        nlohmann::json run = search.runs[i].ToJson();
        run["sequence"] = setup.sequences[i % n].path;
        j["runs"].push_back(run);
      }
      for (size_t v = 0; v < search.values.size(); ++v) {
        const double e = search.mean_error[v];
        j["mean_error"].push_back({{"virtual_baseline", search.values[v]},
                                   {"mean_error", std::isfinite(e) ? nlohmann::json(e) : nlohmann::json(nullptr)}});
      }
      std::cout << j.dump(2) << std::endl;
    } else {
      std::cout << "schedule: " << setup.options.dvso.prediction_timing << "\n";
      std::cout << DescribeTuningMetric(search.metric) << "\n";
      for (size_t k = 0; k < n && n > 1; ++k) std::cout << "#" << k + 1 << ": " << setup.sequences[k].path << "\n";
      std::cout << FormatVariantTable(search.runs);
      if (n > 1) {
        for (size_t v = 0; v < search.values.size(); ++v) {
          std::cout << "b_v=" << BaselineRunLabel(search.values[v]) << ": mean " << TuningMetricName(search.metric)
                    << " over " << n << " sequences "
                    << (std::isfinite(search.mean_error[v]) ? std::to_string(search.mean_error[v]) : "- (lost)")
                    << "\n";
        }
      }
      std::cout << "best virtual baseline: " << search.best << " m (default " << default_bv
                << " m); use it with --virtual-baseline " << search.best << "\n";
    }
  });
}

}  // namespace dvso::cli
