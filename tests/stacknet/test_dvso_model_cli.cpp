// DVSO mode with a TorchScript model through the real binary: the shipped
// model runs online, `tune-baseline --write-model` stamps the tuned virtual
// baseline (paper "tb") into a copy that `dvso odometry` then uses.
#include <gtest/gtest.h>

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "core/trajectory.h"
#include "tests/dvso_cli_runner.h"

namespace dvso {
namespace {

TEST(DvsoModelCli, ShippedModelRunsOnlineAndTunedBaselineIsStamped) {
  const std::string model = std::string(DVSO_TEST_DATA_DIR) + "/../models/stacknet_cpu_main.pt";
  ASSERT_TRUE(std::filesystem::exists(model));
  const std::string dir = testing::FreshSimulatedSequence("dvso_model_cli", 15);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const auto run = testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " + dir + "/out");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("stacknet_cpu_main.pt"), std::string::npos) << run.out;  // the shipped model by default
  EXPECT_EQ(ReadTrajectory(dir + "/out/trajectory.txt", TrajectoryFormat::kKitti).size(), 15u);

  // Tuned on two sequences (here the same one twice: deterministic keyframe-blocking runs, so the mean is checkable).
  const auto tune = testing::RunDvso("tune-baseline --json --values 0.4:0.2:0.8 --sequence " + seq + " --gt " + seq +
                                         "/poses.txt --sequence " + seq + " --gt " + seq + "/poses.txt --out " + dir +
                                         "/tune --model " + model + " --write-model " + dir + "/tuned.pt",
                                     /*merge_stderr=*/false);
  ASSERT_EQ(tune.exit_code, 0) << tune.out;
  const nlohmann::json j = nlohmann::json::parse(tune.out);
  ASSERT_EQ(j["runs"].size(), 6u);  // 3 values x 2 sequences, value-major
  ASSERT_EQ(j["mean_error"].size(), 3u);
  double lowest = std::numeric_limits<double>::infinity(), argmin = 0;
  for (int v = 0; v < 3; ++v) {
    // 15 frames are too short for KITTI segments: the ATE is what is minimised.
    const double a = j["runs"][2 * v]["ate_rmse"].get<double>(), b = j["runs"][2 * v + 1]["ate_rmse"].get<double>();
    EXPECT_NEAR(a, b, 1e-9);
    EXPECT_NEAR(j["mean_error"][v]["mean_error"].get<double>(), 0.5 * (a + b), 1e-9);
    if (0.5 * (a + b) < lowest) {
      lowest = 0.5 * (a + b);
      argmin = j["mean_error"][v]["virtual_baseline"].get<double>();
    }
  }
  const double best = j["best_virtual_baseline"].get<double>();
  EXPECT_NEAR(best, argmin, 1e-9);
  const auto tuned = testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " + dir +
                                      "/tuned_out --model " + dir + "/tuned.pt");
  ASSERT_EQ(tuned.exit_code, 0) << tuned.out;
  EXPECT_NE(tuned.out.find("tuned, paper 'tb', on " + seq + ", " + seq), std::string::npos) << tuned.out;
  // This camera is the training camera's shape (f_x / W), so the stamped b_v comes back unchanged.
  EXPECT_NE(tuned.out.find("virtual baseline " + std::to_string(best).substr(0, 3)), std::string::npos) << tuned.out;
}

}  // namespace
}  // namespace dvso
