// Where one training step's time goes (issue 10: the CPU model's quality is bounded by the steps that fit
// in ~2.5 hours): forward, each loss term, backward and the Adam update, timed separately for a SimpleNet and
// a StackNet stage of a config's network. The batch is synthetic (smooth random images, 2 % labels) at the
// config's input size, so no training data is needed.
//
//   bench_torch_train_step [--config configs/stacknet_cpu_v4_long.yaml] [--steps 12] [--threads 1] [--batch 4]
//
// Prints ms per step for each part and its share of the step, once with the input in NCHW and once in the
// trainer's layout (ToConvolutionLayout: channels-last on the CPU), and the ratio of the two step times.
// The first 2 steps of each are warm-up (not timed).
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "stacknet/config.h"
#include "stacknet/device.h"
#include "stacknet/losses.h"
#include "stacknet/networks.h"
#include "stacknet/trainer.h"

namespace {

using dvso::stacknet::LossOptions;
using dvso::stacknet::LossSwitches;
using dvso::stacknet::StackNet;
using dvso::stacknet::StageOptions;
using dvso::stacknet::StereoBatch;
using Clock = std::chrono::steady_clock;

constexpr int kWarmupSteps = 2;
constexpr double kLabelDensity = 0.02;  // share of pixels with a label, as Stereo DSO labels at this size

StereoBatch SyntheticBatch(int batch, int height, int width) {
  torch::manual_seed(1);
  auto smooth_image = [&] {
    const torch::Tensor coarse = torch::rand({batch, 3, height / 8, width / 8});
    return torch::upsample_bilinear2d(coarse, {height, width}, /*align_corners=*/false).clamp(0, 1);
  };
  StereoBatch b;
  b.left = smooth_image();
  b.right = smooth_image();
  b.left_label = 0.01 + 0.05 * torch::rand({batch, 1, height, width});
  b.right_label = 0.01 + 0.05 * torch::rand({batch, 1, height, width});
  b.left_mask = (torch::rand({batch, 1, height, width}) < kLabelDensity).to(torch::kFloat);
  b.right_mask = (torch::rand({batch, 1, height, width}) < kLabelDensity).to(torch::kFloat);
  return b;
}

// Runs `steps` timed steps of one stage, prints each part's time per step and returns the step's.
double TimeStage(StackNet& model, const StageOptions& stage, const LossOptions& loss, const StereoBatch& batch,
                 int steps) {
  torch::optim::Adam optimizer(dvso::stacknet::PrepareStage(model, stage), torch::optim::AdamOptions(1e-4));
  model->train();
  const LossSwitches all = dvso::stacknet::SwitchesOf(stage);
  // Each term alone, to attribute the loss time (the sum of these is about the total loss's time).
  const std::vector<std::pair<std::string, bool LossSwitches::*>> term_switches = {
      {"unsupervised (eq. 2)", &LossSwitches::unsupervised}, {"supervised (eq. 3)", &LossSwitches::supervised},
      {"left-right (eq. 4)", &LossSwitches::lr},             {"smoothness (eq. 5)", &LossSwitches::smooth},
      {"occlusion (eq. 6)", &LossSwitches::occ}};
  std::vector<std::pair<std::string, LossSwitches>> terms;
  for (const auto& [name, term] : term_switches) {
    LossSwitches only{false, false, false, false, false};
    only.*term = all.*term;
    terms.emplace_back(name, only);
  }
  std::map<std::string, double> ms;
  std::vector<std::string> order = {"forward", "loss (all terms)", "backward", "Adam step"};
  for (const auto& [name, _] : terms) order.push_back("  of which " + name + " fwd+bwd");
  auto since = [](Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); };
  for (int step = 0; step < kWarmupSteps + steps; ++step) {
    const bool timed = step >= kWarmupSteps;
    auto t0 = Clock::now();
    const auto disparities = dvso::stacknet::StageForward(model, stage, batch.left);
    if (timed) ms["forward"] += since(t0);
    t0 = Clock::now();
    const auto total = dvso::stacknet::TotalLoss(disparities, batch, loss, all);
    if (timed) ms["loss (all terms)"] += since(t0);
    optimizer.zero_grad();
    t0 = Clock::now();
    total.total.backward();
    if (timed) ms["backward"] += since(t0);
    t0 = Clock::now();
    optimizer.step();
    if (timed) ms["Adam step"] += since(t0);
    if (!timed) continue;
    // Each term's own forward + backward through the loss alone (the network's outputs detached).
    dvso::stacknet::DisparityPyramid detached;
    for (const auto& d : disparities.left) detached.left.push_back(d.detach().requires_grad_(true));
    for (const auto& d : disparities.right) detached.right.push_back(d.detach().requires_grad_(true));
    for (const auto& [name, only] : terms) {
      t0 = Clock::now();
      const auto one = dvso::stacknet::TotalLoss(detached, batch, loss, only);
      if (one.total.requires_grad()) one.total.backward();
      ms["  of which " + name + " fwd+bwd"] += since(t0);
    }
  }
  double step_ms = 0;
  for (const char* part : {"forward", "loss (all terms)", "backward", "Adam step"}) step_ms += ms[part] / steps;
  std::printf("%s stage '%s': %.0f ms per step (%d steps)\n", stage.model.c_str(), stage.name.c_str(), step_ms, steps);
  for (const auto& part : order) {
    std::printf("  %-44s %8.1f ms  %5.1f %%\n", part.c_str(), ms[part] / steps, 100.0 * ms[part] / steps / step_ms);
  }
  return step_ms;
}

}  // namespace

int main(int argc, char** argv) {
  std::string config_path = "configs/stacknet_cpu_v4_long.yaml";
  int steps = 12, threads = 1, batch_size = 4;
  // Flags come in pairs; a missing value, an unknown flag or a non-integer is refused.
  auto integer = [](const std::string& flag, const std::string& text) {
    size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || value < 1) throw std::invalid_argument(flag + " needs a positive integer, not '" + text + "'");
    return value;
  };
  try {
    for (int i = 1; i < argc; i += 2) {
      const std::string flag = argv[i];
      if (i + 1 >= argc) throw std::invalid_argument(flag + " needs a value");
      const std::string value = argv[i + 1];
      if (flag == "--config") config_path = value;
      else if (flag == "--steps") steps = integer(flag, value);
      else if (flag == "--threads") threads = integer(flag, value);
      else if (flag == "--batch") batch_size = integer(flag, value);
      else throw std::invalid_argument("unknown flag " + flag + " (--config, --steps, --threads, --batch)");
    }
  } catch (const std::invalid_argument& e) {
    std::cerr << "bench_torch_train_step: " << e.what() << "\n";
    return 2;
  }
  // As `dvso train`: the thread budget reaches LibTorch and OpenBLAS alike.
  dvso::stacknet::SelectDevice("cpu", threads);
  const auto config = dvso::stacknet::LoadConfig(config_path, /*check=*/false);  // the data need not exist here
  const int h = static_cast<int>(config.network.input_height), w = static_cast<int>(config.network.input_width);
  std::printf("%s: %dx%d, batch %d, %d intra-op thread(s)\n", config_path.c_str(), w, h, batch_size, threads);
  const StereoBatch nchw_batch = SyntheticBatch(batch_size, h, w);
  std::map<std::string, std::map<bool, double>> step_ms;  // stage name -> channels-last? -> ms per step
  for (const bool channels_last : {false, true}) {
    std::printf("--- input %s\n", channels_last ? "channels-last (the trainer's, ToConvolutionLayout)" : "NCHW");
    StereoBatch batch = nchw_batch;
    if (channels_last) batch.left = dvso::stacknet::ToConvolutionLayout(batch.left, torch::Device(torch::kCPU));
    torch::manual_seed(3);
    StackNet model(config.network);
    // The first semi-supervised stage of each network (every loss term on): the bulk of the schedule.
    for (const char* model_name : {"simple", "stack"}) {
      for (const auto& stage : config.stages) {
        if (stage.model == model_name && stage.use_unsupervised && stage.use_supervised) {
          step_ms[stage.name][channels_last] = TimeStage(model, stage, config.loss, batch, steps);
          break;
        }
      }
    }
  }
  for (const auto& [name, ms] : step_ms) {
    std::printf("stage '%s': NCHW / channels-last step time = %.2f\n", name.c_str(), ms.at(false) / ms.at(true));
  }
  return 0;
}
