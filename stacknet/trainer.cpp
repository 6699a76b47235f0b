#include "stacknet/trainer.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <utility>

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
  const DisparityPyramid disparities = StageForward(model, stage, ToConvolutionLayout(batch.left, batch.left.device()));
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

// Loss sums of one epoch, for its record in epochs.jsonl.
struct EpochSums {
  LossTerms terms;  // the terms summed over the steps (total unused)
  double total = 0;
  int steps = 0;
  void Add(double step_total, const LossTerms& t) {
    terms.unsupervised += t.unsupervised;
    terms.supervised += t.supervised;
    terms.lr += t.lr;
    terms.smooth += t.smooth;
    terms.occ += t.occ;
    total += step_total;
    ++steps;
  }
};

// Keeps the CSV rows up to the checkpoint's global step (drops rows of an
// interrupted tail that a resumed run will redo) and returns an appending
// stream. `resumed_epoch` receives the kept rows of the epoch the checkpoint
// stopped in, so that epoch's record also counts the steps run before the
// interruption (one on its last batch would otherwise log an epoch of 0 steps).
std::ofstream OpenLossCsv(const std::string& path, const TrainingPosition& resume_at, bool resume,
                          EpochSums* resumed_epoch) {
  const std::string header = "stage,stage_name,epoch,batch,global_step,learning_rate,total,unsupervised,supervised,lr,smooth,occ";
  constexpr size_t kColumns = 12;
  std::vector<std::string> kept;
  if (resume && fs::exists(path)) {
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::vector<std::string> cells;
      std::istringstream fields(line);
      for (std::string cell; std::getline(fields, cell, ',');) cells.push_back(cell);
      if (cells.size() != kColumns) continue;  // a row cut short by a crash: dropped like the tail
      int stage = -1, epoch = -1;
      int64_t step = -1;
      double total = 0;
      LossTerms terms;
      try {
        stage = std::stoi(cells[0]);
        epoch = std::stoi(cells[2]);
        step = std::stoll(cells[4]);
        total = std::stod(cells[6]);
        terms.unsupervised = std::stod(cells[7]);
        terms.supervised = std::stod(cells[8]);
        terms.lr = std::stod(cells[9]);
        terms.smooth = std::stod(cells[10]);
        terms.occ = std::stod(cells[11]);
      } catch (const std::exception&) {
        continue;  // unreadable (cut short by a crash): dropped like the tail
      }
      if (step < 0 || step > resume_at.global_step) continue;
      kept.push_back(line);
      if (resume_at.batch > 0 && stage == resume_at.stage && epoch == resume_at.epoch) {
        resumed_epoch->Add(total, terms);
      }
    }
  }
  std::ofstream out(path, std::ios::trunc);
  RequireFile(out.good(), path, "cannot write the loss log");
  out << header << "\n";
  for (const auto& line : kept) out << line << "\n";
  return out;
}

// Keeps the records of the epochs finished before the checkpoint's position and
// returns an appending stream: the epoch a resumed run continues, and every
// later one, are logged again by it (as their CSV rows are dropped), so a
// resume from an older checkpoint or from mid-epoch leaves one record per epoch.
std::ofstream OpenEpochLog(const std::string& path, const TrainingPosition& resume_at, bool resume) {
  std::vector<std::string> kept;
  if (resume && fs::exists(path)) {
    std::ifstream in(path);
    for (std::string line; std::getline(in, line);) {
      const nlohmann::json record = nlohmann::json::parse(line, nullptr, /*allow_exceptions=*/false);
      if (record.is_discarded() || !record.is_object()) continue;  // a line cut short by a crash
      auto integer = [&](const char* key) {
        const auto it = record.find(key);
        return it != record.end() && it->is_number_integer() ? it->get<int64_t>() : int64_t{-1};
      };
      const int64_t stage = integer("stage"), epoch = integer("epoch"), step = integer("global_step");
      const bool before = stage < resume_at.stage || (stage == resume_at.stage && epoch < resume_at.epoch);
      if (stage >= 0 && epoch >= 0 && step >= 0 && step <= resume_at.global_step && before) kept.push_back(line);
    }
  }
  std::ofstream out(path, std::ios::trunc);
  RequireFile(out.good(), path, "cannot write the epoch log");
  for (const auto& line : kept) out << line << "\n";
  return out;
}

// A resume inside a stage continues its epoch order (train.seed), its batches (train.batch_size) and its
// frames (the stage's data) where the checkpoint stopped: with other values the resumed batches would not be
// the interrupted run's, and nothing would say so. At a stage boundary the next stage starts afresh, so those
// may change there (e.g. new settings for the StackNet stages after a SimpleNet stage's checkpoint).
void RequireSameBatchesOnResume(const StackNetConfig& saved, const StackNetConfig& current, const TrainingPosition& at,
                                const std::string& checkpoint) {
  const bool inside_stage = (at.epoch > 0 || at.batch > 0) && at.stage < static_cast<int>(current.stages.size()) &&
                            at.stage < static_cast<int>(saved.stages.size()) &&
                            at.epoch < current.stages[at.stage].epochs;
  if (!inside_stage) return;
  auto require_same = [&](bool same, const std::string& key, const std::string& values) {
    RequireFile(same, checkpoint,
                key + " differs from the checkpoint's config" + values +
                    ": the resumed batches would not be the interrupted run's (restore it, or resume from a stage "
                    "checkpoint)");
  };
  auto values = [](const auto& was, const auto& is) {
    std::ostringstream text;
    text << " (" << was << " there, " << is << " here)";
    return text.str();
  };
  require_same(saved.train.batch_size == current.train.batch_size, "train.batch_size",
               values(saved.train.batch_size, current.train.batch_size));
  require_same(saved.train.seed == current.train.seed, "train.seed", values(saved.train.seed, current.train.seed));
  const StageOptions& stage = current.stages[at.stage];
  const std::string data = stage.data.empty() ? "data." : "datasets." + stage.data + ".";
  const DataOptions& was = saved.DataFor(saved.stages[at.stage]);
  const DataOptions& is = current.DataFor(stage);
  require_same(was.sequences == is.sequences, data + "sequences",
               values(std::to_string(was.sequences.size()) + " sequence(s)",
                      std::to_string(is.sequences.size()) + " sequence(s)"));
  require_same(was.split_file == is.split_file, data + "split_file",
               values("'" + was.split_file + "'", "'" + is.split_file + "'"));
  require_same(is.split_file.empty() || was.split_root == is.split_root, data + "split_root",
               values("'" + was.split_root + "'", "'" + is.split_root + "'"));
  require_same(was.frame_step == is.frame_step, data + "frame_step", values(was.frame_step, is.frame_step));
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
    RequireSameBatchesOnResume(saved_config, config_, saved.position, resume_checkpoint);
    info.position = saved.position;
    info.trained_model = saved.trained_model;
    LoadCheckpointWeights(resume_checkpoint, model_, device_);
    std::cerr << "Resuming from " << resume_checkpoint << " at stage " << info.position.stage << ", epoch "
              << info.position.epoch << ", batch " << info.position.batch << " (step " << info.position.global_step
              << ")\n";
  }
  if (!resume && !train.init_from.empty()) {
    const int copied = LoadWeightsFromExport(train.init_from, model_);
    model_->to(device_);
    std::cerr << "Initialised " << copied << " weight tensors from " << train.init_from << "\n";
  }
  // The first stage's data opens before any output file changes, as the checks above come before it: a
  // refused resume or a missing sequence leaves config.yaml describing the checkpoints beside it, and the logs.
  const TrainingPosition resume_at = info.position;
  std::unique_ptr<const StereoDataset> first_dataset;
  if (resume_at.stage < static_cast<int>(config_.stages.size())) {
    first_dataset = std::make_unique<const StereoDataset>(config_.DataFor(config_.stages[resume_at.stage]),
                                                          config_.network.input_width, config_.network.input_height);
  }
  EnsureDirectory(train.output_dir);
  WriteStreamAtomically(JoinPath(train.output_dir, "config.yaml"), [&](std::ostream& out) { out << config_yaml_; });
  EpochSums resumed_epoch;  // the steps of the checkpoint's epoch before it (resume only)
  std::ofstream csv = OpenLossCsv(JoinPath(train.output_dir, "losses.csv"), resume_at, resume, &resumed_epoch);
  std::ofstream epochs_log = OpenEpochLog(JoinPath(train.output_dir, "epochs.jsonl"), resume_at, resume);

  for (int stage_index = info.position.stage; stage_index < static_cast<int>(config_.stages.size()); ++stage_index) {
    const StageOptions& stage = config_.stages[stage_index];
    const std::unique_ptr<const StereoDataset> opened =
        first_dataset ? std::move(first_dataset)
                      : std::make_unique<const StereoDataset>(config_.DataFor(stage), config_.network.input_width,
                                                              config_.network.input_height);
    const StereoDataset& dataset = *opened;
    std::cerr << "Stage " << stage_index << " '" << stage.name << "' (" << stage.model << "): " << stage.epochs
              << " epoch(s), " << dataset.Describe();
    torch::optim::Adam optimizer(PrepareStage(model_, stage),
                                 torch::optim::AdamOptions(stage.learning_rate)
                                     .betas({train.adam_beta1, train.adam_beta2})
                                     .eps(train.adam_epsilon));
    const bool mid_stage = resume && (info.position.epoch > 0 || info.position.batch > 0);
    if (mid_stage) LoadCheckpointWeights(resume_checkpoint, model_, device_, &optimizer);
    resume = false;
    for (int epoch = info.position.epoch; epoch < stage.epochs; ++epoch) {
      const double lr = stage.LearningRateAt(epoch);
      SetLearningRate(optimizer, lr);
      DataLoader loader(dataset, config_.augment, train.batch_size, train.num_workers, train.seed, stage_index, epoch,
                        info.position.batch, stage.max_steps_per_epoch);
      // After a mid-epoch resume the bar counts the batches this run does, so that its rate and ETA are not
      // the batches before the interruption over the time since the resume.
      const int first_batch = info.position.batch;
      ProgressBar progress(stage.name + " epoch " + std::to_string(epoch + 1) + "/" + std::to_string(stage.epochs) +
                               (first_batch > 0 ? " from batch " + std::to_string(first_batch + 1) + "/" +
                                                      std::to_string(loader.num_batches())
                                                : std::string()),
                           std::max(0, loader.num_batches() - first_batch));
      // The checkpoint's epoch starts from the sums of its steps before the interruption (that epoch only: a
      // config with fewer epochs than the checkpoint's position skips it, and the next stage starts from 0).
      EpochSums sums;
      if (stage_index == resume_at.stage && epoch == resume_at.epoch) sums = std::exchange(resumed_epoch, EpochSums{});
      const int steps_before = sums.steps;  // not timed by this run: `seconds` covers the others (timed_steps)
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
        sums.Add(total, terms);
        csv << stage_index << "," << stage.name << "," << epoch << "," << batch_index << ","
            << info.position.global_step << "," << lr << "," << total << "," << terms.unsupervised << ","
            << terms.supervised << "," << terms.lr << "," << terms.smooth << "," << terms.occ << "\n";
        if (train.progress) progress.Update(batch_index + 1 - first_batch, FormatTerms(terms, total));
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
      const double n = std::max(1, sums.steps);
      const LossTerms& sum = sums.terms;
      if (train.progress) {
        LossTerms mean = sum;
        mean.unsupervised /= n, mean.supervised /= n, mean.lr /= n, mean.smooth /= n, mean.occ /= n;
        progress.Finish(FormatTerms(mean, sums.total / n));
      }
      // An epoch without steps has no losses to record (its means would read as 0).
      if (sums.steps > 0) {
        nlohmann::json record = {{"stage", stage_index},         {"stage_name", stage.name},
                                 {"epoch", epoch},               {"steps", sums.steps},
                                 {"global_step", info.position.global_step},
                                 {"learning_rate", lr},          {"mean_total", sums.total / n},
                                 {"mean_unsupervised", sum.unsupervised / n},
                                 {"mean_supervised", sum.supervised / n},
                                 {"mean_lr", sum.lr / n},        {"mean_smooth", sum.smooth / n},
                                 {"mean_occ", sum.occ / n},      {"seconds", seconds},
                                 {"timed_steps", sums.steps - steps_before}};
        epochs_log << record.dump() << "\n";
        epochs_log.flush();
      }
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
