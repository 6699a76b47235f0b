// End-to-end runs of `dvso eval-odometry` and `dvso eval-depth`: --json prints
// exactly one parseable object, plots are written, bad input is one clear error.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/trajectory.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

using testing::CliRun;
using testing::RunDvso;

using testing::TempDir;

const std::string kGt = std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/04.txt";

TEST(EvalCli, OdometryJsonSim3OnScaledEstimate) {
  TempDir dir("eval_cli_odo");
  Trajectory est = ReadTrajectory(kGt);
  for (StampedPose& p : est.poses) p.T_world_camera.translation() *= 0.5;
  WriteKittiTrajectory(dir / "est.txt", est);
  const CliRun r = RunDvso("eval-odometry --gt " + kGt + " --est " + dir / "est.txt" +
                            " --align sim3 --json --plot-dir " + dir / "plots",
                        false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);  // throws unless exactly one JSON value
  EXPECT_NEAR(j["scale"].get<double>(), 2.0, 1e-6);
  EXPECT_NEAR(j["ate_rmse"].get<double>(), 0.0, 1e-5);
  EXPECT_NEAR(j["t_rel"].get<double>(), 0.0, 1e-4);
  EXPECT_EQ(j["frames"].get<int>(), 271);
  EXPECT_EQ(j["missing_frames"].get<int>(), 0);
  EXPECT_TRUE(fs::exists(dir / "plots/trajectory_xz.png"));
  EXPECT_TRUE(fs::exists(dir / "plots/segment_errors.png"));
}

TEST(EvalCli, OdometryTumFilesReportMissingFrames) {
  TempDir dir("eval_cli_tum");
  Trajectory gt = ReadTrajectory(kGt);
  for (StampedPose& p : gt.poses) p.timestamp = 1.5e9 + 0.1 * p.timestamp;
  Trajectory est;
  for (size_t i = 0; i < gt.size(); ++i) {
    if (i != 17 && i != 18) est.poses.push_back(gt.poses[i]);
  }
  WriteTumTrajectory(dir / "gt.tum", gt);
  WriteTumTrajectory(dir / "est.tum", est);
  const CliRun r = RunDvso("eval-odometry --gt " + dir / "gt.tum" + " --est " + dir / "est.tum", true);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("missing frames    : 2 (GT indices 17-18)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("t_rel"), std::string::npos);
}

TEST(EvalCli, OdometryBadInputIsOneClearError) {
  TempDir dir("eval_cli_bad");
  std::ofstream(dir / "broken.txt") << "1 2 3 4 5\n";
  CliRun r = RunDvso("eval-odometry --gt " + kGt + " --est " + dir / "broken.txt", true);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("dvso: error:"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("broken.txt"), std::string::npos) << r.out;
  r = RunDvso("eval-odometry --gt " + kGt + " --est " + kGt + " --align affine", true);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("affine"), std::string::npos) << r.out;
}

TEST(EvalCli, DepthJsonAndNameMismatch) {
  TempDir dir("eval_cli_depth");
  fs::create_directories(dir / "gt");
  fs::create_directories(dir / "pred");
  cv::Mat gt(10, 20, CV_16U, cv::Scalar(20 * 256));  // disparity 20 px
  cv::Mat pred(10, 20, CV_16U, cv::Scalar(16 * 256)); // disparity 16 px
  ASSERT_TRUE(cv::imwrite(dir / "gt/000000_10.png", gt));
  ASSERT_TRUE(cv::imwrite(dir / "pred/000000_10.png", pred));
  CliRun r = RunDvso("eval-depth --pred " + dir / "pred" + " --gt " + dir / "gt" + " --fxb 400 --json", false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  // depth 25 m predicted for 20 m: abs rel 0.25, rmse 5, delta 1.25 is not < 1.25.
  EXPECT_NEAR(j["abs_rel"].get<double>(), 0.25, 1e-6);
  EXPECT_NEAR(j["rmse"].get<double>(), 5.0, 1e-5);
  EXPECT_NEAR(j["a1"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(j["a2"].get<double>(), 1.0, 1e-12);
  // Median scaling explains the global factor.
  r = RunDvso("eval-depth --pred " + dir / "pred" + " --gt " + dir / "gt" + " --fxb 400 --median-scaling --json",
              false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["abs_rel"].get<double>(), 0.0, 1e-6);
  // Breakdown by GT depth range: 20 m falls into [10, 40); predicted 25 m -> median pred / GT 1.25.
  r = RunDvso("eval-depth --pred " + dir / "pred" + " --gt " + dir / "gt" + " --fxb 400 --ranges 0,10,40 --json",
              false);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json ranges = nlohmann::json::parse(r.out)["ranges"];
  ASSERT_EQ(ranges["per_range"].size(), 2u);
  EXPECT_EQ(ranges["per_range"][0]["pixels"].get<long>(), 0);
  EXPECT_EQ(ranges["per_range"][1]["pixels"].get<long>(), 200);
  EXPECT_NEAR(ranges["all"]["median_pred_over_gt"].get<double>(), 1.25, 1.25e-3);
  r = RunDvso("eval-depth --pred " + dir / "pred" + " --gt " + dir / "gt" + " --fxb 400 --ranges 0,40 --min-gradient 50",
              true);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("--images"), std::string::npos) << r.out;

  ASSERT_TRUE(cv::imwrite(dir / "pred/000001_10.png", pred));
  r = RunDvso("eval-depth --pred " + dir / "pred" + " --gt " + dir / "gt" + " --fxb 400", true);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("000001_10.png"), std::string::npos) << r.out;
  // Disparities without a focal length * baseline cannot become depths.
  r = RunDvso("eval-depth --pred " + dir / "pred" + " --gt " + dir / "gt", true);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("--fxb"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace dvso
