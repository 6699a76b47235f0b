// `dvso export --checkpoint CKPT --out model.pt [--model auto|simple|stack]`:
// traces a trained network to TorchScript (input 1x3xHxW in [0, 1]; output
// left and right disparity at scale 0 in pixels of the input).
// `dvso export --config FILE --random-init --model stack --out model.pt`
// exports an untrained network of that architecture (for `dvso bench`; with
// --training-baseline and --training-fx-over-width also for `odometry --model`).
// `dvso export --stamp OLD.pt --out NEW.pt` copies an export with corrected metadata.
// `dvso export --checkpoint CKPT --weights-only --out W.pt` copies a checkpoint without its Adam state.
// A metadata option that a mode cannot record is an error, never dropped.
#include <iostream>

#include "core/error.h"
#include "pipelines/commands.h"
#include "stacknet/checkpoint.h"
#include "stacknet/config.h"
#include "stacknet/export.h"

namespace dvso::cli {

void AddExportCommand(CLI::App& app) {
  struct Args {
    std::string checkpoint, config, out, stamp, tuned_on;
    double tuned_baseline = 0;
    bool random_init = false;
    bool weights_only = false;
    stacknet::ExportOptions options;
  };
  auto args = std::make_shared<Args>();
  auto* cmd = app.add_subcommand("export", "Export a training checkpoint to TorchScript");
  cmd->add_option("--checkpoint", args->checkpoint, "Checkpoint written by `dvso train`")->check(CLI::ExistingFile);
  cmd->add_option("--config", args->config, "With --random-init: architecture from this YAML config")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--random-init", args->random_init,
                "Export untrained weights (latency benchmarks; give the training camera for `odometry --model`)");
  cmd->add_option("--out", args->out, "Output TorchScript file (.pt)")->required();
  cmd->add_flag("--weights-only", args->weights_only,
                "Instead of exporting: copy --checkpoint without its optimiser state (a third of the size; "
                "`dvso export --checkpoint` reads the copy)");
  cmd->add_option("--training-baseline", args->options.training_baseline,
                  "Training camera baseline in metres (default: read from the first sequence its stages trained on; "
                  "--random-init: none)")
      ->check(NonNegative());
  cmd->add_option("--training-fx-over-width", args->options.training_fx_over_width,
                  "Training camera f_x / image width (default: read from the first sequence its stages trained on; "
                  "--random-init: none)")
      ->check(NonNegative());
  cmd->add_option("--stamp", args->stamp,
                  "Instead of exporting: copy this exported .pt to --out with the training camera metadata")
      ->check(CLI::ExistingFile);
  cmd->add_option("--tuned-baseline", args->tuned_baseline,
                  "With --stamp: the tuned virtual baseline (paper 'tb', training camera, metres; 0 = none)")
      ->check(NonNegative());
  cmd->add_option("--tuned-on", args->tuned_on, "With --stamp and --tuned-baseline: the sequence it was tuned on");
  cmd->add_option("--config-name", args->options.config_name,
                  "The name of the training config (--stamp: for models exported before it was recorded; "
                  "--checkpoint: instead of the recorded one)");
  cmd->add_option("--model", args->options.model,
                  "auto (as trained; --random-init: stack), simple (SimpleNet only) or stack (SimpleNet + "
                  "ResidualNet)");
  cmd->callback([cmd, args] {
    args->options.Check();
    const bool tuned_baseline_given = cmd->count("--tuned-baseline") > 0;
    const bool tuned_on_given = cmd->count("--tuned-on") > 0;
    if (!args->stamp.empty()) {
      // Stamping copies a network that is already exported: the options that choose or build one do nothing.
      for (const char* option : {"--checkpoint", "--config", "--random-init", "--model", "--weights-only"})
        Require(cmd->count(option) == 0, std::string(option) + " exports a network: not with --stamp (it copies one)");
      Require(!tuned_on_given || tuned_baseline_given,
              "--tuned-on names where --tuned-baseline was tuned: give --tuned-baseline too");
      Require(!tuned_on_given || args->tuned_baseline > 0,
              "--tuned-on needs a tuned baseline: --tuned-baseline 0 removes it");
      ModelMetadata metadata = stacknet::ReadModelMetadata(args->stamp);
      if (args->options.training_baseline > 0) metadata.baseline = args->options.training_baseline;
      if (args->options.training_fx_over_width > 0) metadata.fx_over_width = args->options.training_fx_over_width;
      Require(metadata.has_camera(), "--stamp: the model has no training camera: give --training-baseline and "
                                     "--training-fx-over-width");
      if (!args->options.config_name.empty()) metadata.config_name = args->options.config_name;
      if (tuned_baseline_given) {
        metadata.tuned_baseline = args->tuned_baseline;
        metadata.tuned_on = args->tuned_on;
      }
      stacknet::WriteModelWithMetadata(args->stamp, args->out, metadata);
      std::cout << "Wrote " << args->out << " with metadata " << metadata.ToJson() << std::endl;
      return;
    }
    // A tuned baseline belongs to a trained model on a sequence it ran on: stamped afterwards, never exported.
    Require(!tuned_baseline_given && !tuned_on_given,
            "--tuned-baseline / --tuned-on only with --stamp (or `tune-baseline --write-model`)");
    if (args->random_init) {
      Require(!args->config.empty() && args->checkpoint.empty(), "--random-init needs --config (and no --checkpoint)");
      Require(!args->weights_only, "--weights-only copies a --checkpoint: not with --random-init");
      const stacknet::StackNetConfig config = stacknet::LoadConfig(args->config, /*check=*/false);
      // Exported before anything is printed: a refused export leaves only its error line.
      const std::string description = stacknet::ExportRandomInit(config.network, args->out, args->options);
      std::cout << "Exported untrained " << description << std::endl;
      return;
    }
    Require(!args->checkpoint.empty(), "give --checkpoint CKPT (or --config FILE --random-init)");
    Require(args->config.empty(), "--config only with --random-init (a checkpoint carries its own config)");
    if (args->weights_only) {
      // A copy of the checkpoint, not a network: the options that describe an export have nothing to go into.
      for (const char* option : {"--model", "--training-baseline", "--training-fx-over-width", "--config-name"})
        Require(cmd->count(option) == 0, std::string(option) + " describes an export: not with --weights-only");
      stacknet::WriteWeightsOnlyCheckpoint(args->checkpoint, args->out);
      std::cout << "Wrote " << args->out << " (the weights of " << args->checkpoint << ", no optimiser state)"
                << std::endl;
      return;
    }
    const std::string description = stacknet::ExportCheckpoint(args->checkpoint, args->out, args->options);
    std::cout << "Exported " << description << std::endl;
  });
}

}  // namespace dvso::cli
