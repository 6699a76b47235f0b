#include "stacknet/trainer.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/progress.h"
#include "stacknet/config.h"
#include "stacknet/data_loader.h"
#include "stacknet/export.h"
#include "stacknet/dataset.h"
#include "stacknet/device.h"

namespace dvso::stacknet {
namespace fs = std::filesystem;

LossSwitches SwitchesOf(const StageOptions& stage) {
  LossSwitches s;
  s.unsupervised = stage.use_unsupervised;
  s.supervised = stage.use_supervised;
  s.lr = stage.use_lr;
  s.smooth = stage.use_smooth;
  s.occ = stage.use_occ;
  return s;
}

DisparityPyramid StageForward(StackNet& model, const StageOptions& stage, const torch::Tensor& left_image) {
  if (stage.model == "simple") return model->simple_net()->forward(left_image);
  return model->forward(left_image).refined;
}

std::vector<torch::Tensor> PrepareStage(StackNet& model, const StageOptions& stage) {
  if (stage.model == "simple") {
    model->SetSimpleNetFrozen(false);
    return model->simple_net()->parameters();
  }
  model->SetSimpleNetFrozen(true);  // paper 5.1: "we freeze its weights and train StackNet"
  return model->residual_net()->parameters();
}

LossTerms TrainStep(StackNet& model, torch::optim::Adam& optimizer, const StageOptions& stage,
                    const LossOptions& loss, const StereoBatch& batch) {
  model->train();
  const DisparityPyramid disparities = StageForward(model, stage, batch.left);
  LossTerms terms = TotalLoss(disparities, batch, loss, SwitchesOf(stage));
  optimizer.zero_grad();
  terms.total.backward();
  optimizer.step();
  return terms;
}

namespace {

void SetLearningRate(torch::optim::Adam& optimizer, double lr) {
  for (auto& group : optimizer.param_groups()) {
    static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
  }
}

std::string FormatTerms(const LossTerms& t, double total) {
  std::ostringstream s;
  s << std::setprecision(4) << "loss " << total << " (U " << t.unsupervised << " S " << t.supervised << " lr " << t.lr
    << " sm " << t.smooth << " occ " << t.occ << ")";
  return s.str();
}

// Keeps the CSV rows up to `global_step` (drops rows of an interrupted tail
// that a resumed run will redo) and returns an appending stream.
std::ofstream OpenLossCsv(const std::string& path, int64_t keep_up_to_step, bool resume) {
  const std::string header = "stage,stage_name,epoch,batch,global_step,learning_rate,total,unsupervised,supervised,lr,smooth,occ";
  std::vector<std::string> kept;
  if (resume && fs::exists(path)) {
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string cell;
      int64_t step = -1;
      for (int column = 0; column < 5 && std::getline(fields, cell, ','); ++column) {
        if (column == 4) step = std::stoll(cell);
      }
      if (step >= 0 && step <= keep_up_to_step) kept.push_back(line);
    }
  }
  std::ofstream out(path, std::ios::trunc);
  RequireFile(out.good(), path, "cannot write the loss log");
  out << header << "\n";
  for (const auto& line : kept) out << line << "\n";
  return out;
}

}  // namespace

Trainer::Trainer(StackNetConfig config, StopPredicate should_stop)
    : config_(std::move(config)),
      config_yaml_(ConfigToYaml(config_)),
      should_stop_(std::move(should_stop)),
      device_(SelectDevice(config_.train.device, config_.train.num_threads)),
      model_(config_.network) {
  config_.Check();
  torch::manual_seed(config_.train.seed);
  model_ = StackNet(config_.network);  // re-create after seeding: initial weights depend only on the seed
  model_->to(device_);
}

std::string Trainer::LastCheckpointPath() const { return JoinPath(config_.train.output_dir, "checkpoint_last.pt"); }

std::string Trainer::StageCheckpointPath(int stage) const {
  return JoinPath(config_.train.output_dir,
                  "checkpoint_stage" + std::to_string(stage) + "_" + config_.stages[stage].name + ".pt");
}

TrainResult Trainer::Run(const std::string& resume_checkpoint) {
  const TrainOptions& train = config_.train;
  EnsureDirectory(train.output_dir);
  WriteAtomically(JoinPath(train.output_dir, "config.yaml"), [&](const std::string& temp) {
    std::ofstream out(temp);
    out << config_yaml_;
    RequireFile(out.good(), temp, "cannot write the training config");
  });
  TrainResult result;
  CheckpointInfo info;
  info.config_yaml = config_yaml_;
  info.config_name = config_name_;
  bool resume = !resume_checkpoint.empty();
  if (resume) {
    const CheckpointInfo saved = ReadCheckpointInfo(resume_checkpoint);
    const StackNetConfig saved_config = ParseConfig(saved.config_yaml, resume_checkpoint + " (embedded config)");
    Require(ConfigToYaml(StackNetConfig{saved_config.network, {}, {}, {}, {}, {}, {}}) ==
                ConfigToYaml(StackNetConfig{config_.network, {}, {}, {}, {}, {}, {}}),
            resume_checkpoint + ": the network options differ from the config; cannot resume");
    info.position = saved.position;
    info.trained_model = saved.trained_model;
    LoadCheckpointWeights(resume_checkpoint, model_);
    model_->to(device_);
    std::cerr << "Resuming from " << resume_checkpoint << " at stage " << info.position.stage << ", epoch "
              << info.position.epoch << ", batch " << info.position.batch << " (step " << info.position.global_step
              << ")\n";
  }
  if (!resume && !train.init_from.empty()) {
    const int copied = LoadWeightsFromExport(train.init_from, model_);
    model_->to(device_);
    std::cerr << "Initialised " << copied << " weight tensors from " << train.init_from << "\n";
  }
  std::ofstream csv = OpenLossCsv(JoinPath(train.output_dir, "losses.csv"), info.position.global_step, resume);
  std::ofstream epochs_log(JoinPath(train.output_dir, "epochs.jsonl"), resume ? std::ios::app : std::ios::trunc);

  for (int stage_index = info.position.stage; stage_index < static_cast<int>(config_.stages.size()); ++stage_index) {
    const StageOptions& stage = config_.stages[stage_index];
    const StereoDataset dataset(config_.DataFor(stage), config_.network.input_width, config_.network.input_height);
    std::cerr << "Stage " << stage_index << " '" << stage.name << "' (" << stage.model << "): " << stage.epochs
              << " epoch(s), " << dataset.Describe();
    torch::optim::Adam optimizer(PrepareStage(model_, stage),
                                 torch::optim::AdamOptions(stage.learning_rate)
                                     .betas({train.adam_beta1, train.adam_beta2})
                                     .eps(train.adam_epsilon));
    const bool mid_stage = resume && (info.position.epoch > 0 || info.position.batch > 0);
    if (mid_stage) LoadCheckpointWeights(resume_checkpoint, model_, &optimizer);
    resume = false;
    for (int epoch = info.position.epoch; epoch < stage.epochs; ++epoch) {
      const double lr = stage.LearningRateAt(epoch);
      SetLearningRate(optimizer, lr);
      DataLoader loader(dataset, config_.augment, train.batch_size, train.num_workers, train.seed, stage_index, epoch,
                        info.position.batch, stage.max_steps_per_epoch);
      ProgressBar progress(stage.name + " epoch " + std::to_string(epoch + 1) + "/" + std::to_string(stage.epochs),
                           loader.num_batches());
      LossTerms sum;
      int steps = 0;
      double total_sum = 0;
      const auto start = std::chrono::steady_clock::now();
      for (int batch_index = info.position.batch; auto batch = loader.Next(); ++batch_index) {
        const LossTerms terms = TrainStep(model_, optimizer, stage, config_.loss, batch->to(device_));
        const double total = terms.total.item<double>();
        Require(std::isfinite(total), "training diverged: loss is not finite at step " +
                                          std::to_string(info.position.global_step));
        info.trained_model = stage.model;
        info.position.batch = batch_index + 1;
        ++info.position.global_step;
        result.last_loss = total;
        sum.unsupervised += terms.unsupervised;
        sum.supervised += terms.supervised;
        sum.lr += terms.lr;
        sum.smooth += terms.smooth;
        sum.occ += terms.occ;
        total_sum += total;
        ++steps;
        csv << stage_index << "," << stage.name << "," << epoch << "," << batch_index << ","
            << info.position.global_step << "," << lr << "," << total << "," << terms.unsupervised << ","
            << terms.supervised << "," << terms.lr << "," << terms.smooth << "," << terms.occ << "\n";
        if (train.progress) progress.Update(batch_index + 1, FormatTerms(terms, total));
        if (should_stop_ && should_stop_(info.position)) {
          csv.flush();
          SaveCheckpoint(LastCheckpointPath(), model_, &optimizer, info);
          result.interrupted = true;
          result.last_checkpoint = LastCheckpointPath();
          result.position = info.position;
          if (train.progress) progress.Finish("interrupted");
          return result;
        }
      }
      csv.flush();
      const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      const double n = std::max(1, steps);
      if (train.progress) {
        LossTerms mean = sum;
        mean.unsupervised /= n, mean.supervised /= n, mean.lr /= n, mean.smooth /= n, mean.occ /= n;
        progress.Finish(FormatTerms(mean, total_sum / n));
      }
      nlohmann::json record = {{"stage", stage_index},         {"stage_name", stage.name},
                               {"epoch", epoch},               {"steps", steps},
                               {"global_step", info.position.global_step},
                               {"learning_rate", lr},          {"mean_total", total_sum / n},
                               {"mean_unsupervised", sum.unsupervised / n},
                               {"mean_supervised", sum.supervised / n},
                               {"mean_lr", sum.lr / n},        {"mean_smooth", sum.smooth / n},
                               {"mean_occ", sum.occ / n},      {"seconds", seconds}};
      epochs_log << record.dump() << "\n";
      epochs_log.flush();
      // Next position: the following epoch of this stage (or the next stage).
      info.position.batch = 0;
      info.position.epoch = epoch + 1;
      if (info.position.epoch >= stage.epochs) {
        info.position.stage = stage_index + 1;
        info.position.epoch = 0;
      }
      SaveCheckpoint(LastCheckpointPath(), model_, &optimizer, info);
      result.last_checkpoint = LastCheckpointPath();
    }
    if (stage.epochs == 0 || info.position.stage != stage_index + 1) {
      info.position = TrainingPosition{stage_index + 1, 0, 0, info.position.global_step};
    }
    SaveCheckpoint(StageCheckpointPath(stage_index), model_, nullptr, info);
    info.position.epoch = 0;
    info.position.batch = 0;
  }
  const std::string final_path = JoinPath(train.output_dir, "checkpoint_final.pt");
  SaveCheckpoint(final_path, model_, nullptr, info);
  result.finished = true;
  result.last_checkpoint = final_path;
  result.position = info.position;
  return result;
}

}  // namespace dvso::stacknet
