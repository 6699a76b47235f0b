// `dvso train --config FILE [--resume] [--resume-from CKPT] [--init-from MODEL] [--output-dir DIR]`:
// trains SimpleNet / StackNet through the config's stages (paper 5.1).
// Ctrl-C writes a checkpoint and stops; --resume continues exactly there.
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>

#include "core/error.h"
#include "pipelines/commands.h"
#include "stacknet/config.h"
#include "stacknet/trainer.h"

namespace dvso::cli {
namespace {

// Written by the SIGINT handler, read by the trainer after every step. A
// signal handler can only reach state like this; it is local to this file.
std::atomic<bool> g_stop_requested{false};

extern "C" void RequestStop(int) { g_stop_requested.store(true); }

struct TrainArgs {
  std::string config;
  std::string output_dir;
  bool resume = false;
  std::string resume_from;
  std::string init_from;
  std::vector<std::string> sequences;
};

void RunTrain(const TrainArgs& args) {
  stacknet::StackNetConfig config = stacknet::LoadConfig(args.config, /*check=*/false);
  if (!args.output_dir.empty()) config.train.output_dir = args.output_dir;
  if (!args.init_from.empty()) config.train.init_from = args.init_from;
  try {
    if (!args.sequences.empty()) stacknet::SetDefaultSequences(&config, args.sequences);
    config.Check();
  } catch (const Error& e) {
    throw Error(args.config, e.what());
  }
  std::cout << "# dvso train: config " << args.config << "\n" << stacknet::ConfigToYaml(config) << std::flush;
  stacknet::Trainer trainer(config, [](const stacknet::TrainingPosition&) { return g_stop_requested.load(); });
  trainer.set_config_name(std::filesystem::path(args.config).stem().string());
  std::string resume = args.resume_from;
  if (args.resume && resume.empty()) {
    resume = trainer.LastCheckpointPath();
    Require(std::filesystem::exists(resume), "--resume: no checkpoint at " + resume);
  }
  g_stop_requested.store(false);
  auto previous = std::signal(SIGINT, RequestStop);
  stacknet::TrainResult result;
  try {
    result = trainer.Run(resume);
  } catch (...) {
    std::signal(SIGINT, previous);
    throw;
  }
  std::signal(SIGINT, previous);
  if (result.interrupted) {
    std::cout << "Interrupted at stage " << result.position.stage << ", epoch " << result.position.epoch << ", batch "
              << result.position.batch << "; checkpoint " << result.last_checkpoint
              << " (continue with --resume)" << std::endl;
    return;
  }
  std::cout << "Training finished after " << result.position.global_step << " steps; final checkpoint "
            << result.last_checkpoint << std::endl;
}

}  // namespace

void AddTrainCommand(CLI::App& app) {
  auto args = std::make_shared<TrainArgs>();
  auto* cmd = app.add_subcommand("train", "Train SimpleNet / StackNet from a YAML config (paper 3, 5.1)");
  cmd->add_option("--config", args->config, "YAML config (see configs/stacknet_*.yaml)")->required()->check(CLI::ExistingFile);
  cmd->add_option("--output-dir", args->output_dir, "Override train.output_dir");
  cmd->add_option("--sequence", args->sequences,
                  "Train the stages that use the default data on this sequence instead (replaces data.sequences "
                  "and data.split_file; repeatable; an error when every stage names a dataset)");
  cmd->add_flag("--resume", args->resume, "Continue from <output_dir>/checkpoint_last.pt");
  cmd->add_option("--resume-from", args->resume_from, "Continue from this checkpoint")->check(CLI::ExistingFile);
  cmd->add_option("--init-from", args->init_from,
                  "Start from the weights of a `dvso export` model (fine-tuning; overrides train.init_from)")
      ->check(CLI::ExistingFile);
  cmd->callback([args] { RunTrain(*args); });
}

}  // namespace dvso::cli
