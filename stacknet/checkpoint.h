// Training checkpoints: model weights + Adam state + position in the schedule
// + the full config, in one torch::serialize archive written atomically.
#pragma once

#include <torch/torch.h>

#include <string>

#include "stacknet/networks.h"
#include "stacknet/options.h"

namespace dvso::stacknet {

// Where training stands; the next batch to run is (stage, epoch, batch).
struct TrainingPosition {
  int stage = 0;
  int epoch = 0;
  int batch = 0;
  int64_t global_step = 0;
};

struct CheckpointInfo {
  std::string config_yaml;            // ConfigToYaml() of the run
  TrainingPosition position;
  std::string trained_model = "simple";  // "simple" or "stack": which network export should use
  std::string config_name;              // the config file's name without .yaml; "" in checkpoints before session 10
};

void SaveCheckpoint(const std::string& path, StackNet& model, torch::optim::Adam* optimizer,
                    const CheckpointInfo& info);
// Reads config and position only (to build the model before loading weights).
CheckpointInfo ReadCheckpointInfo(const std::string& path);
// Loads weights (and the optimiser state when `optimizer` is given and the
// checkpoint has one for the same stage) onto `device`, the device the model
// is on: LibTorch's load swaps in each parameter's data as read and builds the
// Adam state from the archive, so tensors read onto another device would leave
// the model and its optimiser off the batches' device. Throws dvso::Error naming the file.
void LoadCheckpointWeights(const std::string& path, StackNet& model, const torch::Device& device,
                           torch::optim::Adam* optimizer = nullptr);

// Builds the StackNet of a checkpoint with its weights (CPU, eval use).
StackNet LoadModelFromCheckpoint(const std::string& path, CheckpointInfo* info = nullptr);

// Copies a checkpoint without its Adam state (a third of the size: what a lent GPU machine sends back, and what
// `dvso export` needs), same weights, config and position. Throws dvso::Error naming the file.
void WriteWeightsOnlyCheckpoint(const std::string& checkpoint_path, const std::string& out_path);

}  // namespace dvso::stacknet
