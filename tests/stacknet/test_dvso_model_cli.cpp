// DVSO mode with a TorchScript model through the real binary: the shipped
// model runs online, `tune-baseline --write-model` stamps the tuned virtual
// baseline (paper "tb") into a copy that `dvso odometry` then uses.
#include <gtest/gtest.h>

#include <filesystem>
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

  const auto tune = testing::RunDvso("tune-baseline --values 0.4:0.2:0.8 --sequence " + seq + " --gt " + seq +
                                     "/poses.txt --out " + dir + "/tune --model " + model + " --write-model " + dir +
                                     "/tuned.pt");
  ASSERT_EQ(tune.exit_code, 0) << tune.out;
  const auto best_at = tune.out.find("best virtual baseline: ");
  ASSERT_NE(best_at, std::string::npos) << tune.out;
  const double best = std::stod(tune.out.substr(best_at + 23));
  const auto tuned = testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " + dir +
                                      "/tuned_out --model " + dir + "/tuned.pt");
  ASSERT_EQ(tuned.exit_code, 0) << tuned.out;
  EXPECT_NE(tuned.out.find("tuned, paper 'tb'"), std::string::npos) << tuned.out;
  // This camera is the training camera's shape (f_x / W), so the stamped b_v comes back unchanged.
  EXPECT_NE(tuned.out.find("virtual baseline " + std::to_string(best).substr(0, 3)), std::string::npos) << tuned.out;
}

}  // namespace
}  // namespace dvso
