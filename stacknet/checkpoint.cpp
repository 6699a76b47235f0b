#include "stacknet/checkpoint.h"

#include <filesystem>

#include "core/error.h"
#include "core/fs_util.h"
#include "stacknet/config.h"

namespace dvso::stacknet {

void SaveCheckpoint(const std::string& path, StackNet& model, torch::optim::Adam* optimizer,
                    const CheckpointInfo& info) {
  torch::serialize::OutputArchive archive;
  torch::serialize::OutputArchive model_archive;
  model->save(model_archive);
  archive.write("model", model_archive);
  archive.write("has_optimizer", c10::IValue(optimizer != nullptr));
  if (optimizer) {
    torch::serialize::OutputArchive optimizer_archive;
    optimizer->save(optimizer_archive);
    archive.write("optimizer", optimizer_archive);
  }
  archive.write("config_yaml", c10::IValue(info.config_yaml));
  archive.write("trained_model", c10::IValue(info.trained_model));
  archive.write("config_name", c10::IValue(info.config_name));
  archive.write("stage", c10::IValue(static_cast<int64_t>(info.position.stage)));
  archive.write("epoch", c10::IValue(static_cast<int64_t>(info.position.epoch)));
  archive.write("batch", c10::IValue(static_cast<int64_t>(info.position.batch)));
  archive.write("global_step", c10::IValue(info.position.global_step));
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  if (!parent.empty()) EnsureDirectory(parent.string());
  WriteAtomically(path, [&](const std::string& temp) { archive.save_to(temp); });
}

namespace {
torch::serialize::InputArchive OpenArchive(const std::string& path, const torch::Device& device) {
  RequireFile(std::filesystem::exists(path), path, "checkpoint not found");
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path, device);
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a readable checkpoint: ") + e.what_without_backtrace());
  }
  return archive;
}
}  // namespace

CheckpointInfo ReadCheckpointInfo(const std::string& path) {
  torch::serialize::InputArchive archive = OpenArchive(path, torch::kCPU);
  CheckpointInfo info;
  c10::IValue value;
  try {
    archive.read("config_yaml", value);
    info.config_yaml = value.toStringRef();
    archive.read("trained_model", value);
    info.trained_model = value.toStringRef();
    archive.read("stage", value);
    info.position.stage = static_cast<int>(value.toInt());
    archive.read("epoch", value);
    info.position.epoch = static_cast<int>(value.toInt());
    archive.read("batch", value);
    info.position.batch = static_cast<int>(value.toInt());
    archive.read("global_step", value);
    info.position.global_step = value.toInt();
  } catch (const c10::Error& e) {
    throw Error(path, std::string("not a dvso StackNet checkpoint: ") + e.what_without_backtrace());
  }
  // Optional: checkpoints written before the config name was recorded lack it.
  if (archive.try_read("config_name", value)) info.config_name = value.toStringRef();
  return info;
}

void LoadCheckpointWeights(const std::string& path, StackNet& model, const torch::Device& device,
                           torch::optim::Adam* optimizer) {
  torch::serialize::InputArchive archive = OpenArchive(path, device);
  try {
    torch::serialize::InputArchive model_archive;
    archive.read("model", model_archive);
    model->load(model_archive);
    c10::IValue has_optimizer;
    archive.read("has_optimizer", has_optimizer);
    if (optimizer && has_optimizer.toBool()) {
      torch::serialize::InputArchive optimizer_archive;
      archive.read("optimizer", optimizer_archive);
      optimizer->load(optimizer_archive);
    }
  } catch (const c10::Error& e) {
    throw Error(path, std::string("checkpoint does not match the network: ") + e.what_without_backtrace());
  }
}

StackNet LoadModelFromCheckpoint(const std::string& path, CheckpointInfo* info_out) {
  const CheckpointInfo info = ReadCheckpointInfo(path);
  const StackNetConfig config = ParseConfig(info.config_yaml, path + " (embedded config)");
  StackNet model(config.network);
  LoadCheckpointWeights(path, model, torch::kCPU);
  model->eval();
  if (info_out) *info_out = info;
  return model;
}

void WriteWeightsOnlyCheckpoint(const std::string& checkpoint_path, const std::string& out_path) {
  CheckpointInfo info;
  StackNet model = LoadModelFromCheckpoint(checkpoint_path, &info);
  SaveCheckpoint(out_path, model, nullptr, info);
}

}  // namespace dvso::stacknet
