// The training schedule of paper 5.1: a list of stages (SimpleNet semi-sup on
// K_o -> self-sup on K_r -> supervised-only on K_o; then StackNet with SimpleNet
// frozen over the same schedule), Adam with per-stage learning rate and halving
// steps, checkpoints every epoch and on request (Ctrl-C), exact resume, a
// progress bar with the loss terms, and CSV/JSON loss logs.
#pragma once

#include <torch/torch.h>

#include <functional>
#include <string>

#include "stacknet/checkpoint.h"
#include "stacknet/losses.h"
#include "stacknet/networks.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// Loss switches of a stage.
LossSwitches SwitchesOf(const StageOptions& stage);

// Forward pass of the network a stage trains: SimpleNet alone for "simple",
// the full StackNet (SimpleNet frozen by the caller) for "stack".
DisparityPyramid StageForward(StackNet& model, const StageOptions& stage, const torch::Tensor& left_image);

// Parameters a stage optimises (SimpleNet's or ResidualNet's); also sets the freezing.
std::vector<torch::Tensor> PrepareStage(StackNet& model, const StageOptions& stage);

// One optimisation step on one batch; returns the loss terms before the step.
LossTerms TrainStep(StackNet& model, torch::optim::Adam& optimizer, const StageOptions& stage,
                    const LossOptions& loss, const StereoBatch& batch);

struct TrainResult {
  bool interrupted = false;     // stopped on request; checkpoint written
  bool finished = false;        // all stages done
  std::string last_checkpoint;  // path of the newest checkpoint
  TrainingPosition position;    // where a resume would continue
  double last_loss = 0;         // total loss of the last step
};

class Trainer {
 public:
  // Polled after every step with the position of the next batch; true = write
  // a checkpoint and stop (the CLI answers SIGINT with it; tests stop at a step).
  using StopPredicate = std::function<bool(const TrainingPosition&)>;
  explicit Trainer(StackNetConfig config, StopPredicate should_stop = nullptr);
  // Runs the whole schedule; resume_checkpoint = "" starts from scratch.
  TrainResult Run(const std::string& resume_checkpoint = "");
  StackNet& model() { return model_; }

  // Recorded in every checkpoint and from there in the exported model's metadata
  // (`dvso train` passes the config file's name without .yaml).
  void set_config_name(std::string name) { config_name_ = std::move(name); }

  std::string LastCheckpointPath() const;
  std::string StageCheckpointPath(int stage) const;

 private:
  StackNetConfig config_;
  std::string config_yaml_;
  std::string config_name_;
  StopPredicate should_stop_;
  torch::Device device_;
  StackNet model_;
};

}  // namespace dvso::stacknet
