// scripts/gpu/stage_steps.py: how the GPU script (scripts/gpu/train_on_device.sh) fits a training schedule into the
// minutes a lent device has. The scaled schedule is what a GPU session trains, once, with no time to find out
// afterwards that an epoch was capped by its data or a halving epoch left behind.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace {

const std::string kStageSteps = std::string(DVSO_TEST_DATA_DIR) + "/../scripts/gpu/stage_steps.py";

// A sequence folder with `frames` (empty) PNG files in image_2, which is all the scaler counts.
std::string FakeSequence(const fs::path& dir, int frames) {
  fs::create_directories(dir / "image_2");
  for (int i = 0; i < frames; ++i) std::ofstream(dir / "image_2" / (std::to_string(i) + ".png")) << "";
  return dir.string();
}

dvso::testing::CliRun RunStageSteps(const std::string& args) {
  return dvso::testing::RunCommand("python3 " + kStageSteps + " " + args);
}

YAML::Node Stage(const YAML::Node& stages, const std::string& name) {
  for (const YAML::Node& stage : stages) {
    if (stage["name"].as<std::string>() == name) return stage;
  }
  ADD_FAILURE() << "no stage " << name;
  return YAML::Node();
}

}  // namespace

TEST(GpuStageSteps, ScalesEveryStageByOneFactorAndGrowsEpochsWhereTheDataEnds) {
  const fs::path dir = dvso::testing::ScratchDir("gpu_stage_steps");
  const std::string big = FakeSequence(dir / "big", 80);    // 80 frames / batch 4 = 20 batches per epoch
  const std::string small = FakeSequence(dir / "small", 8);  // 2 batches per epoch
  // The stages sit in the base file: the scaler resolves `base:` as the config loader does.
  std::ofstream(dir / "base.yaml") << "train: {batch_size: 4}\n"
                                   << "data: {sequences: [" << big << "]}\n"
                                   << "datasets: {K_r: {sequences: [" << small << "]}}\n"
                                   << "stages:\n"
                                   << "  - {name: a, model: simple, epochs: 4, max_steps_per_epoch: 10,"
                                      " lr_halving_start: 2, lr_halving_every: 1}\n"
                                   << "  - {name: b, model: simple, data: K_r, epochs: 2, max_steps_per_epoch: 2}\n"
                                   << "  - {name: c, model: stack, epochs: 1, max_steps_per_epoch: 10}\n";
  std::ofstream(dir / "config.yaml") << "base: base.yaml\ntrain: {seed: 3}\n";
  const std::string out = (dir / "scaled.yaml").string();
  // `stage_steps.py scale` of config.yaml at 1 s per SimpleNet and 2 s per StackNet step.
  auto scale = [&](double budget, const std::string& epoch_overhead = "") {
    const auto run = RunStageSteps("scale " + (dir / "config.yaml").string() + " " + out + " 1 2 " +
                                   std::to_string(budget) + " " + epoch_overhead);
    EXPECT_EQ(run.exit_code, 0) << run.out;
    return run.exit_code;
  };
  // Planned time at 1 s per SimpleNet and 2 s per StackNet step: 40 + 4 + 2 * 10 = 64 s. The scaler takes the
  // largest factor whose schedule fits 0.9 * budget (0.9: what the probe does not time), so a budget of
  // 2 * 64 / 0.9 s (+ 1 s, less than any step more would cost) doubles every stage.
  ASSERT_EQ(scale(2 * 64 / 0.9 + 1), 0);
  const YAML::Node scaled = YAML::LoadFile(out);
  EXPECT_EQ(scaled["base"].as<std::string>(), fs::absolute(dir / "config.yaml").string());
  const YAML::Node stages = scaled["stages"];
  ASSERT_EQ(stages.size(), 3u);
  // a: 80 steps in epochs of 20 (twice the steps per epoch fits the data): epochs and halving epochs unchanged.
  EXPECT_EQ(Stage(stages, "a")["max_steps_per_epoch"].as<int>(), 20);
  EXPECT_EQ(Stage(stages, "a")["epochs"].as<int>(), 4);
  EXPECT_EQ(Stage(stages, "a")["lr_halving_start"].as<int>(), 2);
  // b: 8 steps, but its data has only 2 batches per epoch: 4 epochs of 2, not 2 epochs capped at 2.
  EXPECT_EQ(Stage(stages, "b")["max_steps_per_epoch"].as<int>(), 2);
  EXPECT_EQ(Stage(stages, "b")["epochs"].as<int>(), 4);
  // c: 20 steps in the 20 batches of one epoch.
  EXPECT_EQ(Stage(stages, "c")["max_steps_per_epoch"].as<int>(), 20);
  EXPECT_EQ(Stage(stages, "c")["epochs"].as<int>(), 1);

  // Four times the steps: a's epochs cannot grow past 20 steps, so it gets 8 epochs, and its halving epochs move
  // with them (from the 3rd of 4 epochs, every epoch, to the 5th of 8, every 2nd).
  ASSERT_EQ(scale(4 * 64 / 0.9 + 1), 0);
  const YAML::Node a = Stage(YAML::LoadFile(out)["stages"], "a");
  EXPECT_EQ(a["max_steps_per_epoch"].as<int>(), 20);
  EXPECT_EQ(a["epochs"].as<int>(), 8);
  EXPECT_EQ(a["lr_halving_start"].as<int>(), 4);
  EXPECT_EQ(a["lr_halving_every"].as<int>(), 2);

  // With 10 s per epoch besides the steps (checkpoints), the same budget buys fewer steps: 7 epochs cost 70 of the
  // 0.9 * 142 = 128 s, so the steps get ~(128 - 70) / 64 ~ 0.9x the plan (49 steps), not 2x (128).
  ASSERT_EQ(scale(2 * 64 / 0.9 + 1, "10"), 0);
  const YAML::Node with_overhead = YAML::LoadFile(out)["stages"];
  int steps = 0, epochs = 0;
  for (const YAML::Node& stage : with_overhead) {
    steps += stage["epochs"].as<int>() * stage["max_steps_per_epoch"].as<int>();
    epochs += stage["epochs"].as<int>();
  }
  EXPECT_LT(steps, 64);
  EXPECT_GT(steps, 40);
  EXPECT_LE(epochs, 7);

  // The probe: one SimpleNet and one StackNet stage of two 15-step epochs, with the config's settings.
  const auto probe_run = RunStageSteps("probe " + (dir / "config.yaml").string() + " " + out);
  ASSERT_EQ(probe_run.exit_code, 0) << probe_run.out;
  const YAML::Node probe = YAML::LoadFile(out)["stages"];
  ASSERT_EQ(probe.size(), 2u);
  EXPECT_EQ(probe[0]["model"].as<std::string>(), "simple");
  EXPECT_EQ(probe[1]["model"].as<std::string>(), "stack");
  EXPECT_EQ(probe[0]["epochs"].as<int>(), 2);
  EXPECT_EQ(probe[0]["max_steps_per_epoch"].as<int>(), 15);
  EXPECT_FALSE(probe[0]["lr_halving_start"]);

  // Sequences that are not rendered yet: an error, not a schedule of one-step epochs.
  fs::remove_all(dir / "small");
  const auto refused = RunStageSteps("scale " + (dir / "config.yaml").string() + " " + out + " 1 2 100");
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.out.find("no images"), std::string::npos) << refused.out;
}
