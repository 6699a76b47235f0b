// TorchScript export by tracing. The C++ module's forward is traced with a
// mirrored torch::jit::Module as `self`: the mirror holds the very same
// parameter tensors, so the tracer records them as module attributes (not
// constants) and the result is an ordinary scripted module that
// torch::jit::load and Python's torch.jit.load both run.
//
// Exported interface: forward(image: 1x3xHxW float in [0, 1]) ->
// (left_disparity, right_disparity), each Nx1xHxW, in pixels of the input at
// scale 0. All resampling is by scale factor, so other sizes (multiples of 32)
// work too. Attributes input_height / input_width give the training size;
// max_disparity (and, in a StackNet export, residual_leaky_slope and
// standardize_residual_inputs) the network options of those names that are no
// parameters but change what the weights compute (LoadWeightsFromExport checks them).
//
// Metadata: the file carries the extra file `dvso_metadata.json`
// (core/disparity_conversion.h ModelMetadata: input size, training baseline,
// training f_x / width, config name, model kind), from which the odometry
// derives the virtual baseline for any camera. Python reads it with
//   extra = {"dvso_metadata.json": ""}
//   model = torch.jit.load("model.pt", _extra_files=extra)
//   json.loads(extra["dvso_metadata.json"])
#pragma once

#include <torch/script.h>
#include <torch/torch.h>

#include <string>

#include "core/disparity_conversion.h"
#include "stacknet/networks.h"

namespace dvso::stacknet {

// Scale-0 disparities in pixels: SimpleNet's (use_residual = false) or StackNet's.
std::pair<torch::Tensor, torch::Tensor> InferPixels(StackNet& model, bool use_residual, const torch::Tensor& image);

// Traces the model into a TorchScript module (CPU, eval mode).
torch::jit::Module TraceStackNet(StackNet& model, bool use_residual, int input_height, int input_width);

// Name of the metadata entry in the TorchScript archive's extra files.
inline constexpr const char* kModelMetadataFile = "dvso_metadata.json";

struct ExportOptions {
  std::string model = "auto";  // auto (as trained: stack if ResidualNet was trained) | simple | stack
  double training_baseline = 0;       // training camera baseline (m); 0 = from TrainingCameraFromConfig
  double training_fx_over_width = 0;  // training camera f_x / width; 0 = from the same sequence
  std::string config_name;            // training config's name; "" = the checkpoint's (random init: none)
  void Check() const;
};

// The training camera of a config: the first sequence its stages trained on
// (DataFor of each stage, in stage order: `sequences` or a split file's drives)
// that is on this machine, through the pair training reads (OpenTrainingSequence:
// a raw drive's colour pair). Sequences and split files that do not exist are
// skipped (false when none is left); one that exists but cannot be read throws.
bool TrainingCameraFromConfig(const std::string& config_yaml, double* baseline, double* fx_over_width);

// torch::jit::load with the one error every command gives for a file that is not
// TorchScript (dvso::Error naming it). `extra` (optional) receives the named extra files.
torch::jit::Module LoadTorchScript(const std::string& path, const torch::Device& device,
                                   torch::jit::ExtraFilesMap* extra = nullptr);

// Inference memory layout on CPU: the 4-D (convolution) weights of `module` are
// made channels-last (NHWC), as ToConvolutionLayout (device.h) makes the input.
// LibTorch's oneDNN convolutions then run without reordering every weight and
// activation from NCHW on each call: about 7 % less time per forward on 2 cores
// (`dvso bench`, shipped model, 640x192); the outputs are the same numbers.
// CUDA modules are left as they are. (Training keeps NCHW weights: channels-last
// weights made LibTorch 1.13's convolution backward corrupt the heap.)
void UseInferenceLayout(torch::jit::Module& module, const torch::Device& device);

// A TorchScript file from `dvso export`, loaded once: the module and its
// metadata (the JSON extra file; the input size from the module's attributes
// input_width / input_height when it has them, the size it was traced for).
struct LoadedModel {
  torch::jit::Module module;
  ModelMetadata metadata;
};
LoadedModel LoadModel(const std::string& model_path, const torch::Device& device);

// LoadModel(...).metadata on the CPU. Throws dvso::Error.
ModelMetadata ReadModelMetadata(const std::string& model_path);

// Re-saves an exported TorchScript file with the given metadata (e.g. to stamp
// the training camera onto a model exported before metadata existed).
void WriteModelWithMetadata(const std::string& in_path, const std::string& out_path, const ModelMetadata& metadata);

// Loads a training checkpoint, traces it and saves TorchScript to out_path.
// Returns a one-line description (network, size, parameters).
std::string ExportCheckpoint(const std::string& checkpoint_path, const std::string& out_path,
                             const ExportOptions& options = {});

// Initialises `model` from the weights of a file written by `dvso export`
// (fine-tuning the shipped model on one's own labels, or continuing a run whose
// checkpoints are gone). Parameters are matched by name (the export's
// `a_b_c` for the module's `a.b.c`) and must have the same shapes: a file of
// another architecture is an error naming it, never a partial load. A SimpleNet
// export sets SimpleNet only (the ResidualNet keeps its initialisation). The
// non-parameter options the export records (see above) must equal the
// network's (model->network_options()), else an error naming file and option;
// exports from before they were recorded load unchecked.
// Returns the number of tensors copied.
int LoadWeightsFromExport(const std::string& model_path, StackNet& model);

// Exports a randomly initialised network of the given architecture (latency
// benchmarks need no trained weights). options.model: simple or stack (auto =
// stack). The metadata carries options' training camera and config name as
// given, nothing from a config's sequences: both camera values or neither (a
// file with one is refused by the odometry all the same).
std::string ExportRandomInit(const NetworkOptions& network, const std::string& out_path,
                             const ExportOptions& options = {});

}  // namespace dvso::stacknet
