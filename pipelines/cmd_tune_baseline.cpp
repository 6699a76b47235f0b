// `dvso tune-baseline`: the paper's grid search of the virtual stereo baseline
// ("tb") on a sequence with ground truth: full DVSO per value, the value with
// the lowest unaligned t_rel wins.
#include <iostream>

#include "core/error.h"
#include "pipelines/commands.h"
#include "pipelines/dvso_experiments.h"

namespace dvso::cli {

void AddTuneBaselineCommand(CLI::App& app) {
  struct Args {
    ExperimentArgs experiment;
    std::string values;
    std::string write_model;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("tune-baseline", "Grid search of the DVSO virtual baseline b_v on a sequence with GT");
  AddExperimentOptions(cmd, &args->experiment);
  cmd->add_option("--values", args->values, "start:step:end in metres (default: +-20 % around the model's b_v)");
  cmd->add_option("--write-model", args->write_model,
                  "Write a copy of the --model carrying the best b_v (paper 'tb'); dvso odometry then uses it");
  cmd->callback([args] {
    Require(args->write_model.empty() || !args->experiment.predictions.model.empty(),
            "--write-model needs --model");
    const ExperimentSetup setup = OpenExperiment(args->experiment);
    const double default_bv = setup.predictions.untuned_virtual_baseline;
    const std::vector<double> grid = BaselineGrid(args->values, default_bv);
    double best = 0;
    const std::vector<VariantResult> results =
        TuneVirtualBaseline(setup, grid, args->experiment.count, args->experiment.out, &best, !args->experiment.json);
    if (!args->write_model.empty()) {
      ModelMetadata metadata = setup.predictions.metadata;
      const PinholeCamera& cam = setup.sequence->camera().left;
      metadata.tuned_baseline = TrainingCameraBaseline(metadata, best, cam.fx, cam.width);
      metadata.tuned_on = args->experiment.sequence + (args->experiment.count > 0
                                                           ? " (first " + std::to_string(args->experiment.count) + " frames)"
                                                           : std::string());
      WriteModelWithTunedBaseline(args->experiment.predictions.model, args->write_model, metadata);
      (args->experiment.json ? std::cerr : std::cout) << "wrote " << args->write_model << " (tuned baseline "
                                                      << metadata.tuned_baseline << " m for the training camera)\n";
    }
    if (args->experiment.json) {
      nlohmann::json j;
      j["default_virtual_baseline"] = default_bv;
      j["best_virtual_baseline"] = best;
      j["prediction_timing"] = setup.options.dvso.prediction_timing;
      for (const VariantResult& r : results) j["runs"].push_back(r.ToJson());
      std::cout << j.dump(2) << std::endl;
    } else {
      std::cout << "schedule: " << setup.options.dvso.prediction_timing << "\n"
                << FormatVariantTable(results) << "best virtual baseline: " << best << " m (default " << default_bv
                << " m); use it with --virtual-baseline " << best << "\n";
    }
  });
}

}  // namespace dvso::cli
