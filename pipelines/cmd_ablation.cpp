// `dvso ablation`: the paper's Table 3 on one sequence with ground truth:
// mono (Sim(3)-aligned reference), in, in+vs, in+vs+lr, in+vs+tb, full
// (in+vs+lr+tb); t_rel / r_rel unaligned (KITTI protocol), Sim(3) scale,
// ATE and ms/frame per row. tb uses --tuned-baseline, else the model's tuned
// baseline (`dvso tune-baseline --write-model`), else a grid search on this
// very sequence (said in the output: the paper tunes on training sequences).
// --tune-values is validated even when no search runs, so a typo is never ignored.
#include <iostream>

#include "core/error.h"
#include "core/fs_util.h"
#include "pipelines/commands.h"
#include "pipelines/dvso_experiments.h"

namespace dvso::cli {

namespace {

struct AblationArgs {
  ExperimentArgs experiment;
  double tuned_baseline = 0;
  std::string tune_values;  // grid for tb when no --tuned-baseline
};

void Run(const AblationArgs& args) {
  const ExperimentSetup setup = OpenExperiment(args.experiment);
  const double default_bv = setup.default_virtual_baseline;
  // Before any run, and whether or not the search below is needed.
  const std::vector<double> tune_grid = BaselineGrid(args.tune_values, default_bv, "--tune-values");
  const std::string& out = args.experiment.out;
  std::ostream& log = args.experiment.json ? std::cerr : std::cout;
  const ExperimentSequence& sequence = setup.sequences.front();
  log << "dvso ablation: " << sequence.path << ", predictions: " << setup.predictions.description
      << ", schedule: " << setup.options.dvso.prediction_timing << "\n";

  double tuned = args.tuned_baseline;
  std::string tuned_how = "given (--tuned-baseline)";
  if (!(tuned > 0) && setup.predictions.tuned) {
    tuned = setup.predictions.virtual_baseline;
    tuned_how = "the model's, tuned on " + setup.predictions.metadata.tuned_on;
  }
  if (!(tuned > 0)) {
    const BaselineSearch search =
        TuneVirtualBaseline(setup, tune_grid, args.experiment.count, JoinPath(out, "tune"), !args.experiment.json);
    tuned = search.best;
    tuned_how = std::string("grid search on this sequence, lowest ") + TuningMetricName(search.metric);
  }
  log << "virtual baseline: default " << default_bv << " m, tuned " << tuned << " m (" << tuned_how << ")\n";

  struct Variant {
    const char* name;
    vo::OdometryMode mode;
    bool vs, lr, tb;
  };
  const Variant variants[] = {
      {"mono", vo::OdometryMode::kMono, false, false, false},   {"in", vo::OdometryMode::kDvso, false, false, false},
      {"in+vs", vo::OdometryMode::kDvso, true, false, false},   {"in+vs+lr", vo::OdometryMode::kDvso, true, true, false},
      {"in+vs+tb", vo::OdometryMode::kDvso, true, false, true}, {"full", vo::OdometryMode::kDvso, true, true, true},
  };
  std::vector<VariantResult> results;
  for (const Variant& v : variants) {
    vo::OdometryOptions options = setup.options;
    options.window.use_virtual_stereo = v.vs;
    options.dvso.left_right_check = v.lr;
    options.dvso.virtual_baseline = v.tb ? tuned : default_bv;
    log << "running " << v.name << " ..." << std::endl;
    results.push_back(RunVariant(v.name, *sequence.reader, sequence.gt, v.mode, options,
                                 v.mode == vo::OdometryMode::kDvso ? setup.predictions.source.get() : nullptr,
                                 args.experiment.count, JoinPath(out, v.name)));
  }
  if (args.experiment.json) {
    nlohmann::json j;
    j["sequence"] = sequence.path;
    j["predictions"] = setup.predictions.description;
    j["prediction_timing"] = setup.options.dvso.prediction_timing;
    j["virtual_baseline_default"] = default_bv;
    j["virtual_baseline_tuned"] = tuned;
    j["tuned_by"] = tuned_how;
    for (const VariantResult& r : results) j["variants"].push_back(r.ToJson());
    std::cout << j.dump(2) << std::endl;
  } else {
    std::cout << "\n" << FormatVariantTable(results);
  }
}

}  // namespace

void AddAblationCommand(CLI::App& app) {
  auto args = std::make_shared<AblationArgs>();
  auto* cmd = app.add_subcommand("ablation", "DVSO ablation (paper Table 3) on one sequence with ground truth");
  AddExperimentOptions(cmd, &args->experiment, /*many_sequences=*/false);
  cmd->add_option("--tuned-baseline", args->tuned_baseline,
                  "b_v for the tb rows (metres); default: grid search on this sequence")
      ->check(Positive());
  cmd->add_option("--tune-values", args->tune_values, "Grid for that search, start:step:end (default: +-20 %)");
  cmd->callback([args] { Run(*args); });
}

}  // namespace dvso::cli
