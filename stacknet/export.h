// TorchScript export by tracing. The C++ module's forward is traced with a
// mirrored torch::jit::Module as `self`: the mirror holds the very same
// parameter tensors, so the tracer records them as module attributes (not
// constants) and the result is an ordinary scripted module that
// torch::jit::load and Python's torch.jit.load both run.
//
// Exported interface: forward(image: 1x3xHxW float in [0, 1]) ->
// (left_disparity, right_disparity), each Nx1xHxW, in pixels of the input at
// scale 0. All resampling is by scale factor, so other sizes (multiples of 32)
// work too. Attributes input_height / input_width give the training size.
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <string>

#include "stacknet/networks.h"

namespace dvso::stacknet {

// Scale-0 disparities in pixels: SimpleNet's (use_residual = false) or StackNet's.
std::pair<torch::Tensor, torch::Tensor> InferPixels(StackNet& model, bool use_residual, const torch::Tensor& image);

// Traces the model into a TorchScript module (CPU, eval mode).
torch::jit::Module TraceStackNet(StackNet& model, bool use_residual, int input_height, int input_width);

struct ExportOptions {
  std::string model = "auto";  // auto (as trained: stack if ResidualNet was trained) | simple | stack
  void Check() const;
};

// Loads a training checkpoint, traces it and saves TorchScript to out_path.
// Returns a one-line description (network, size, parameters).
std::string ExportCheckpoint(const std::string& checkpoint_path, const std::string& out_path,
                             const ExportOptions& options = {});

// Exports a randomly initialised network of the given architecture (latency
// benchmarks need no trained weights). model: "simple" or "stack".
std::string ExportRandomInit(const NetworkOptions& network, const std::string& model, const std::string& out_path);

}  // namespace dvso::stacknet
