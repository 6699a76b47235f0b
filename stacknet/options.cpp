#include "stacknet/options.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace dvso::stacknet {

void NetworkOptions::Check() const {
  Require(encoder_depth == 18 || encoder_depth == 34 || encoder_depth == 50,
          "network.encoder_depth must be 18, 34 or 50");
  Require(width_multiplier > 0 && width_multiplier <= 4, "network.width_multiplier must be in (0, 4]");
  Require(input_height >= 32 && input_height % 32 == 0, "network.input_height must be a positive multiple of 32");
  Require(input_width >= 32 && input_width % 32 == 0, "network.input_width must be a positive multiple of 32");
  Require(max_disparity > 0 && max_disparity <= 1, "network.max_disparity must be in (0, 1]");
  Require(residual_leaky_slope >= 0 && residual_leaky_slope < 1, "network.residual_leaky_slope must be in [0, 1)");
  Require(residual_blocks >= 4 && residual_blocks % 4 == 0, "network.residual_blocks must be a multiple of 4");
  Require(initial_disparity >= 0 && initial_disparity < max_disparity,
          "network.initial_disparity must be in [0, max_disparity)");
  Require(normalization == "group" || normalization == "none", "network.normalization must be group or none");
}

void LossOptions::Check() const {
  Require(alpha_u >= 0 && alpha_s >= 0 && alpha_lr >= 0 && alpha_smooth >= 0 && alpha_occ >= 0,
          "loss weights must be >= 0");
  Require(ssim_alpha >= 0 && ssim_alpha <= 1, "loss.ssim_alpha must be in [0, 1]");
  Require(berhu_fraction > 0 && berhu_fraction <= 1, "loss.berhu_fraction must be in (0, 1]");
  Require(num_scales >= 1 && num_scales <= 4, "loss.num_scales must be in [1, 4]");
}

void DataOptions::Check() const {
  Require(!sequences.empty() || !split_file.empty(), "data: give `sequences` or `split_file`");
  Require(gt_sample_fraction > 0 && gt_sample_fraction <= 1, "data.gt_sample_fraction must be in (0, 1]");
  Require(frame_step >= 1, "data.frame_step must be >= 1");
  // A split lists its frames itself; StereoDataset reads every line of it and would ignore the step.
  Require(split_file.empty() || frame_step == 1,
          "data.frame_step (" + std::to_string(frame_step) +
              ") applies to `sequences` only; a split_file lists its frames: set frame_step to 1 (named datasets "
              "inherit it from data:)");
}

void AugmentOptions::Check() const {
  auto range = [](double lo, double hi, const char* what) {
    Require(lo > 0 && lo <= hi, std::string("augment.") + what + " range must satisfy 0 < min <= max");
  };
  range(gamma_min, gamma_max, "gamma");
  range(brightness_min, brightness_max, "brightness");
  range(color_min, color_max, "color");
  Require(probability >= 0 && probability <= 1, "augment.probability must be in [0, 1]");
  Require(flip_probability >= 0 && flip_probability <= 1, "augment.flip_probability must be in [0, 1]");
  Require(grey_probability >= 0 && grey_probability <= 1, "augment.grey_probability must be in [0, 1]");
}

void StageOptions::Check() const {
  Require(model == "simple" || model == "stack", "stage '" + name + "': model must be 'simple' or 'stack'");
  // The name is a column of losses.csv, which a resume reads back by comma.
  Require(name.find_first_of(",\n\"") == std::string::npos, "stage '" + name + "': a stage name has no commas or quotes");
  Require(epochs >= 0, "stage '" + name + "': epochs must be >= 0");
  Require(learning_rate > 0, "stage '" + name + "': learning_rate must be > 0");
  Require(lr_halving_every >= 0, "stage '" + name + "': lr_halving_every must be >= 0");
  Require(max_steps_per_epoch >= 0, "stage '" + name + "': max_steps_per_epoch must be >= 0");
  Require(use_unsupervised || use_supervised || use_lr || use_smooth || use_occ,
          "stage '" + name + "': at least one loss term must be on");
}

double StageOptions::LearningRateAt(int epoch) const {
  if (lr_halving_start < 0 || epoch < lr_halving_start) return learning_rate;
  int halvings = 1;
  if (lr_halving_every > 0) halvings += (epoch - lr_halving_start) / lr_halving_every;
  return learning_rate * std::pow(0.5, halvings);
}

void TrainOptions::Check() const {
  Require(batch_size >= 1, "train.batch_size must be >= 1");
  Require(num_workers >= 1, "train.num_workers must be >= 1");
  Require(adam_beta1 >= 0 && adam_beta1 < 1 && adam_beta2 >= 0 && adam_beta2 < 1, "train.adam_beta* must be in [0, 1)");
  Require(adam_epsilon > 0, "train.adam_epsilon must be > 0");
  Require(device == "auto" || device == "cpu" || device == "cuda", "train.device must be auto, cpu or cuda");
  Require(num_threads >= 0, "train.num_threads must be >= 0");
  Require(!output_dir.empty(), "train.output_dir must not be empty");
}

void StackNetConfig::Check() const {
  network.Check();
  loss.Check();
  augment.Check();
  train.Check();
  Require(!stages.empty(), "config: `stages` must list at least one stage");
  bool default_data_needed = false;
  for (const auto& stage : stages) {
    stage.Check();
    if (stage.data.empty()) {
      default_data_needed = true;
    } else {
      bool found = false;
      for (const auto& [name, options] : datasets) found = found || name == stage.data;
      Require(found, "stage '" + stage.name + "': unknown dataset '" + stage.data + "'");
    }
  }
  if (default_data_needed) data.Check();
  for (const auto& [name, options] : datasets) {
    try {
      options.Check();
    } catch (const Error& e) {
      throw Error("datasets." + name + ": " + e.what());  // which of the datasets
    }
  }
}

const DataOptions& StackNetConfig::DataFor(const StageOptions& stage) const {
  if (stage.data.empty()) return data;
  for (const auto& [name, options] : datasets) {
    if (name == stage.data) return options;
  }
  throw Error("unknown dataset '" + stage.data + "'");
}

}  // namespace dvso::stacknet
