#include "stacknet/export.h"

#include <torch/csrc/jit/frontend/tracer.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "stacknet/checkpoint.h"
#include "stacknet/config.h"
#include "stacknet/dataset.h"
#include "stacknet/warping.h"

namespace dvso::stacknet {
namespace fs = std::filesystem;

void ExportOptions::Check() const {
  Require(model == "auto" || model == "simple" || model == "stack", "export model must be auto, simple or stack");
  Require(training_baseline >= 0 && training_fx_over_width >= 0, "export training camera values must be >= 0");
}

bool TrainingCameraFromConfig(const std::string& config_yaml, double* baseline, double* fx_over_width) {
  const StackNetConfig config = ParseConfig(config_yaml, "(embedded config)");
  // The data the stages trained on, in stage order (config.data only where a stage used it: a
  // config's default sequences may be a camera the model never saw).
  std::vector<const DataOptions*> used;
  for (const StageOptions& stage : config.stages) {
    const DataOptions* data = &config.DataFor(stage);
    if (std::find(used.begin(), used.end(), data) == used.end()) used.push_back(data);
  }
  for (const DataOptions* data : used) {
    // A split file or sequence that is not on this machine any more is skipped; one that is here but
    // cannot be read (a corrupt calibration) is an error, not a reason to take another sequence's camera.
    if (!data->split_file.empty() && !fs::exists(data->split_file)) continue;
    for (const std::string& path : TrainingSequenceRoots(*data)) {
      if (!fs::exists(path)) continue;
      const std::unique_ptr<SequenceReader> sequence = OpenTrainingSequence(path);
      const StereoCamera& cam = sequence->camera();
      if (!(cam.baseline > 0)) continue;
      *baseline = cam.baseline;
      *fx_over_width = cam.left.fx / cam.left.width;
      return true;
    }
  }
  return false;
}

torch::jit::Module LoadTorchScript(const std::string& path, const torch::Device& device,
                                   torch::jit::ExtraFilesMap* extra) {
  try {
    return extra != nullptr ? torch::jit::load(path, device, *extra) : torch::jit::load(path, device);
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a TorchScript model: ") + e.what_without_backtrace());
  }
}

void UseInferenceLayout(torch::jit::Module& module, const torch::Device& device) {
  if (!device.is_cpu()) return;
  torch::NoGradGuard no_grad;
  for (torch::Tensor parameter : module.parameters()) {
    if (parameter.dim() == 4) parameter.set_data(parameter.contiguous(at::MemoryFormat::ChannelsLast));
  }
}

LoadedModel LoadModel(const std::string& model_path, const torch::Device& device) {
  torch::jit::ExtraFilesMap extra{{kModelMetadataFile, ""}};
  LoadedModel loaded{LoadTorchScript(model_path, device, &extra), {}};
  const std::string& json = extra[kModelMetadataFile];
  if (!json.empty()) loaded.metadata = ModelMetadata::FromJson(json, model_path + " (" + kModelMetadataFile + ")");
  const torch::jit::Module& module = loaded.module;
  if (module.hasattr("input_width") && module.hasattr("input_height")) {
    loaded.metadata.input_width = static_cast<int>(module.attr("input_width").toInt());
    loaded.metadata.input_height = static_cast<int>(module.attr("input_height").toInt());
  }
  return loaded;
}

ModelMetadata ReadModelMetadata(const std::string& model_path) { return LoadModel(model_path, torch::kCPU).metadata; }

void WriteModelWithMetadata(const std::string& in_path, const std::string& out_path, const ModelMetadata& metadata) {
  torch::jit::Module module = LoadTorchScript(in_path, torch::kCPU);
  const torch::jit::ExtraFilesMap extra{{kModelMetadataFile, metadata.ToJson()}};
  WriteAtomically(out_path, [&](const std::string& temp) { module.save(temp, extra); });
}

namespace {
// The name a module parameter gets in the exported mirror (TraceStackNet).
std::string ExportedParameterName(std::string name) {
  std::replace(name.begin(), name.end(), '.', '_');
  return name;
}
// ResidualNet's parameters, which a SimpleNet export does not carry.
bool IsResidualParameter(const std::string& name) { return name.rfind("residual.", 0) == 0; }

// The network options that change what the weights compute without being parameters: recorded by
// TraceStackNet as attributes named like their `network.` config keys, checked by LoadWeightsFromExport.
constexpr const char* kMaxDisparityAttribute = "max_disparity";  // SimpleNet's sigmoid scale (fraction of the width)
constexpr const char* kLeakySlopeAttribute = "residual_leaky_slope";
constexpr const char* kStandardizeAttribute = "standardize_residual_inputs";

std::string OptionValue(const c10::IValue& value) {
  if (value.isBool()) return value.toBool() ? "true" : "false";
  std::ostringstream text;
  text << value.toDouble();
  return text.str();
}

// The export's value of one such option against the target network's. Exact: a value written the same
// way in two configs parses to the same double, and the export keeps it bit for bit. Exports written
// before these attributes existed have none: they load as before, unchecked (the shipped models/*.pt).
void RequireSameOption(const torch::jit::Module& module, const std::string& model_path, const char* name,
                       const c10::IValue& target) {
  if (!module.hasattr(name)) return;
  const c10::IValue exported = module.attr(name);
  const bool same = target.isBool() ? exported.toBool() == target.toBool() : exported.toDouble() == target.toDouble();
  RequireFile(same, model_path,
              std::string("was exported with network.") + name + " " + OptionValue(exported) +
                  ", the config's network has " + OptionValue(target) + ": its weights would compute something else");
}
}  // namespace

int LoadWeightsFromExport(const std::string& model_path, StackNet& model) {
  const torch::jit::Module module = LoadTorchScript(model_path, torch::kCPU);
  std::map<std::string, torch::Tensor> exported;
  for (const auto& item : module.named_parameters(/*recurse=*/false)) exported.emplace(item.name, item.value);
  RequireFile(!exported.empty(), model_path, "has no parameters: not a model written by `dvso export`");
  const bool has_residual = module.hasattr("uses_residual") && module.attr("uses_residual").toBool();
  const NetworkOptions& network = model->network_options();
  RequireSameOption(module, model_path, kMaxDisparityAttribute, c10::IValue(network.max_disparity));
  // A SimpleNet export leaves the ResidualNet as initialised, so its options are the config's alone.
  if (has_residual) {
    RequireSameOption(module, model_path, kLeakySlopeAttribute, c10::IValue(network.residual_leaky_slope));
    RequireSameOption(module, model_path, kStandardizeAttribute, c10::IValue(network.standardize_residual_inputs));
  }
  torch::NoGradGuard no_grad;
  int copied = 0;
  for (const auto& item : model->named_parameters()) {
    // A SimpleNet export: the ResidualNet keeps its initialisation.
    if (IsResidualParameter(item.key()) && !has_residual) continue;
    const auto it = exported.find(ExportedParameterName(item.key()));
    RequireFile(it != exported.end(), model_path,
                "has no weight '" + item.key() + "': exported from another architecture than the config's network");
    RequireFile(it->second.sizes() == item.value().sizes(), model_path,
                "weight '" + item.key() + "' has another shape than the config's network (another width or depth)");
    item.value().copy_(it->second.to(item.value().device()));
    exported.erase(it);
    ++copied;
  }
  RequireFile(exported.empty(), model_path,
              "has weights the config's network does not (e.g. '" + (exported.empty() ? "" : exported.begin()->first) +
                  "'): another architecture");
  return copied;
}

std::pair<torch::Tensor, torch::Tensor> InferPixels(StackNet& model, bool use_residual, const torch::Tensor& image) {
  const DisparityPyramid d =
      use_residual ? model->forward(image).refined : model->simple_net()->forward(image);
  // Fractions of the width -> pixels; the width is taken from the tensor (shape-free trace).
  const torch::Tensor width = WidthAsTensor(d.left[0]);
  return {d.left[0] * width, d.right[0] * width};
}

torch::jit::Module TraceStackNet(StackNet& model, bool use_residual, int input_height, int input_width) {
  model->eval();
  model->to(torch::kCPU);
  torch::jit::Module mirror(use_residual ? "DvsoStackNet" : "DvsoSimpleNet");
  for (const auto& item : model->named_parameters()) {
    // A SimpleNet export carries only SimpleNet's weights.
    if (!use_residual && IsResidualParameter(item.key())) continue;
    const std::string name = ExportedParameterName(item.key());
    // Same tensor object: the tracer maps it to `self.<name>` instead of a constant.
    mirror.register_parameter(name, item.value(), /*is_buffer=*/false);
  }
  mirror.register_attribute("input_height", c10::IntType::get(), c10::IValue(static_cast<int64_t>(input_height)));
  mirror.register_attribute("input_width", c10::IntType::get(), c10::IValue(static_cast<int64_t>(input_width)));
  mirror.register_attribute("uses_residual", c10::BoolType::get(), c10::IValue(use_residual));
  const NetworkOptions& network = model->network_options();
  mirror.register_attribute(kMaxDisparityAttribute, c10::FloatType::get(), c10::IValue(network.max_disparity));
  // ResidualNet's options only where its weights travel: a SimpleNet export has no ResidualNet to describe.
  if (use_residual) {
    mirror.register_attribute(kLeakySlopeAttribute, c10::FloatType::get(), c10::IValue(network.residual_leaky_slope));
    mirror.register_attribute(kStandardizeAttribute, c10::BoolType::get(),
                              c10::IValue(network.standardize_residual_inputs));
  }

  const torch::Tensor example = torch::rand({1, 3, input_height, input_width});
  auto traced_fn = [&](torch::jit::Stack inputs) -> torch::jit::Stack {
    const auto [left, right] = InferPixels(model, use_residual, inputs.at(0).toTensor());
    return {c10::ivalue::Tuple::create({left, right})};
  };
  torch::NoGradGuard no_grad;
  auto traced = torch::jit::tracer::trace({c10::IValue(example)}, traced_fn,
                                          [](const torch::autograd::Variable&) { return std::string(); },
                                          /*strict=*/false, /*force_outplace=*/false, &mirror);
  std::shared_ptr<torch::jit::Graph> graph = traced.first->graph;
  const c10::QualifiedName method_name(*mirror.type()->name(), "forward");
  torch::jit::Function* forward = mirror._ivalue()->compilation_unit()->create_function(method_name, graph);
  mirror.type()->addMethod(forward);
  return mirror;
}

namespace {
std::string SaveTraced(StackNet& model, bool use_residual, const NetworkOptions& network, ModelMetadata metadata,
                       const std::string& out_path) {
  torch::jit::Module module = TraceStackNet(model, use_residual, network.input_height, network.input_width);
  metadata.input_width = network.input_width;
  metadata.input_height = network.input_height;
  metadata.model_kind = use_residual ? "stack" : "simple";
  const torch::jit::ExtraFilesMap extra{{kModelMetadataFile, metadata.ToJson()}};
  WriteAtomically(out_path, [&](const std::string& temp) { module.save(temp, extra); });
  int64_t parameters = 0;
  for (const auto& p : use_residual ? model->parameters() : model->simple_net()->parameters()) parameters += p.numel();
  std::ostringstream description;
  description << (use_residual ? "StackNet" : "SimpleNet") << " (ResNet-" << network.encoder_depth << ", width x"
              << network.width_multiplier << ", " << network.input_width << "x" << network.input_height << ", "
              << parameters << " parameters) -> " << out_path;
  return description.str();
}
}  // namespace

std::string ExportRandomInit(const NetworkOptions& network, const std::string& out_path, const ExportOptions& options) {
  network.Check();
  options.Check();
  // Half a training camera would make a file that looks usable yet is refused by `odometry --model`.
  Require((options.training_baseline > 0) == (options.training_fx_over_width > 0),
          "random-init export: give both --training-baseline and --training-fx-over-width, or neither");
  ModelMetadata metadata;
  metadata.baseline = options.training_baseline;
  metadata.fx_over_width = options.training_fx_over_width;
  metadata.config_name = options.config_name;
  // Untrained: "auto" (as trained) has no training to follow, so it is the full network.
  const bool use_residual = options.model != "simple";
  StackNet net(network);
  return SaveTraced(net, use_residual, network, metadata, out_path);
}

std::string ExportCheckpoint(const std::string& checkpoint_path, const std::string& out_path,
                             const ExportOptions& options) {
  options.Check();
  CheckpointInfo info;
  StackNet model = LoadModelFromCheckpoint(checkpoint_path, &info);
  const StackNetConfig config = ParseConfig(info.config_yaml, checkpoint_path + " (embedded config)");
  const bool use_residual = options.model == "stack" || (options.model == "auto" && info.trained_model == "stack");
  ModelMetadata metadata;
  // A name given wins; checkpoints from before the config name was recorded only know where they were trained.
  metadata.config_name = !options.config_name.empty() ? options.config_name
                         : info.config_name.empty()    ? config.train.output_dir
                                                       : info.config_name;
  metadata.baseline = options.training_baseline;
  metadata.fx_over_width = options.training_fx_over_width;
  if (!metadata.has_camera()) {
    double baseline = 0, fx_over_width = 0;
    if (TrainingCameraFromConfig(info.config_yaml, &baseline, &fx_over_width)) {
      if (!(metadata.baseline > 0)) metadata.baseline = baseline;
      if (!(metadata.fx_over_width > 0)) metadata.fx_over_width = fx_over_width;
    }
  }
  Require(metadata.has_camera(),
          checkpoint_path + ": training camera unknown (none of the sequences its stages trained on is on this "
                            "machine): pass --training-baseline and --training-fx-over-width");
  return SaveTraced(model, use_residual, config.network, metadata, out_path);
}

}  // namespace dvso::stacknet
