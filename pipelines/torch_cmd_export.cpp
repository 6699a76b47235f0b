// `dvso export --checkpoint CKPT --out model.pt [--model auto|simple|stack]`:
// traces a trained network to TorchScript (input 1x3xHxW in [0, 1]; output
// left and right disparity at scale 0 in pixels of the input).
// `dvso export --config FILE --random-init --model stack --out model.pt`
// exports an untrained network of that architecture (for `dvso bench`).
#include <iostream>

#include "core/error.h"
#include "pipelines/commands.h"
#include "stacknet/config.h"
#include "stacknet/export.h"

namespace dvso::cli {

void AddExportCommand(CLI::App& app) {
  struct Args {
    std::string checkpoint, config, out, stamp, tuned_on, config_name;
    double tuned_baseline = -1;
    bool random_init = false;
    stacknet::ExportOptions options;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("export", "Export a training checkpoint to TorchScript");
  cmd->add_option("--checkpoint", args->checkpoint, "Checkpoint written by `dvso train`")->check(CLI::ExistingFile);
  cmd->add_option("--config", args->config, "With --random-init: architecture from this YAML config")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--random-init", args->random_init, "Export untrained weights (latency benchmarks)");
  cmd->add_option("--out", args->out, "Output TorchScript file (.pt)")->required();
  cmd->add_option("--training-baseline", args->options.training_baseline,
                  "Training camera baseline in metres (default: read from the config's sequences)");
  cmd->add_option("--training-fx-over-width", args->options.training_fx_over_width,
                  "Training camera f_x / image width (default: read from the config's sequences)");
  cmd->add_option("--stamp", args->stamp,
                  "Instead of exporting: copy this exported .pt to --out with the training camera metadata")
      ->check(CLI::ExistingFile);
  cmd->add_option("--tuned-baseline", args->tuned_baseline,
                  "With --stamp: the tuned virtual baseline (paper 'tb', training camera, metres; 0 = none)")
      ->check(NonNegative());
  cmd->add_option("--tuned-on", args->tuned_on, "With --stamp and --tuned-baseline: the sequence it was tuned on");
  cmd->add_option("--config-name", args->config_name,
                  "With --stamp: the name of the training config (models exported before it was recorded)");
  cmd->add_option("--model", args->options.model,
                  "auto (as trained), simple (SimpleNet only) or stack (SimpleNet + ResidualNet)");
  cmd->callback([args] {
    if (!args->stamp.empty()) {
      ModelMetadata metadata = stacknet::ReadModelMetadata(args->stamp);
      if (args->options.training_baseline > 0) metadata.baseline = args->options.training_baseline;
      if (args->options.training_fx_over_width > 0) metadata.fx_over_width = args->options.training_fx_over_width;
      Require(metadata.has_camera(), "--stamp: the model has no training camera: give --training-baseline and "
                                     "--training-fx-over-width");
      if (!args->config_name.empty()) metadata.config_name = args->config_name;
      if (args->tuned_baseline >= 0) {
        metadata.tuned_baseline = args->tuned_baseline;
        metadata.tuned_on = args->tuned_on;
      }
      stacknet::WriteModelWithMetadata(args->stamp, args->out, metadata);
      std::cout << "Wrote " << args->out << " with metadata " << metadata.ToJson() << std::endl;
      return;
    }
    if (args->random_init) {
      Require(!args->config.empty() && args->checkpoint.empty(), "--random-init needs --config (and no --checkpoint)");
      const stacknet::StackNetConfig config = stacknet::LoadConfig(args->config, /*check=*/false);
      const std::string model = args->options.model == "auto" ? "stack" : args->options.model;
      std::cout << "Exported untrained " << stacknet::ExportRandomInit(config.network, model, args->out) << std::endl;
      return;
    }
    Require(!args->checkpoint.empty(), "give --checkpoint CKPT (or --config FILE --random-init)");
    std::cout << "Exported " << stacknet::ExportCheckpoint(args->checkpoint, args->out, args->options) << std::endl;
  });
}

}  // namespace dvso::cli
