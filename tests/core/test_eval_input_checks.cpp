// Inputs the evaluation must refuse or read correctly rather than score
// silently: non-finite .npy predictions, 16-bit colour PNG maps, trajectory
// rows that hold no rotation; and the fx * baseline eval-depth uses (the
// colour pair of a calib.txt, none at all for depth against depth).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/eval_depth.h"
#include "core/trajectory.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

using testing::CliRun;
using testing::RunDvso;
using testing::TempDir;

// A split file of `lines` lines (the drives need not exist: evaluation reads only the %06d.png maps).
std::string WriteSplit(const TempDir& dir, int lines) {
  const std::string path = dir / "split.txt";
  std::ofstream out(path);
  for (int i = 0; i < lines; ++i) out << "2011_09_26/2011_09_26_drive_0002_sync " << i << " l\n";
  return path;
}

// A NaN or inf in a network's .npy output made 0 was scored as a prediction at max_depth (80 m): the
// evaluation refuses it, naming the file, the row and the pixel; the odometry's disparity sources keep
// reading it as "no disparity" (the default of NpyDisparityStack::Frame).
// A KITTI GT without --gt-times is timed by frame index, a TUM estimate by seconds: at 10 Hz every 10th
// pose pairs by chance, and the run reported an ATE of that pairing. Fewer than half paired is an error
// that names the remedy; with the GT's times the same files evaluate.
TEST(EvalInputChecks, TwoTimeBasesThatMeetByChanceAreAnError) {
  TempDir dir("eval_time_bases");
  std::ofstream gt(dir / "gt.txt"), tum(dir / "est.tum"), times(dir / "times.txt");
  for (int i = 0; i < 60; ++i) {
    gt << "1 0 0 0 0 1 0 0 0 0 1 " << 1.0 * i << "\n";
    tum << 0.1 * i << " 0 0 " << 1.0 * i << " 0 0 0 1\n";
    times << 0.1 * i << "\n";
  }
  gt.close(), tum.close(), times.close();
  const CliRun wrong = RunDvso("eval-odometry --gt " + dir / "gt.txt" + " --est " + dir / "est.tum");
  EXPECT_EQ(wrong.exit_code, 1);
  EXPECT_NE(wrong.out.find("of 60 estimated poses match"), std::string::npos) << wrong.out;
  EXPECT_NE(wrong.out.find("--gt-times"), std::string::npos) << wrong.out;
  const CliRun right =
      RunDvso("eval-odometry --gt " + dir / "gt.txt" + " --gt-times " + dir / "times.txt" + " --est " + dir / "est.tum");
  EXPECT_EQ(right.exit_code, 0) << right.out;
}

TEST(EvalInputChecks, NonFiniteNpyPredictionIsAnErrorNamingFileAndPixel) {
  TempDir dir("eval_npy_nan");
  fs::create_directories(dir / "gt");
  const cv::Mat gt_depth(6, 8, CV_32F, cv::Scalar(10.0f));
  WriteKittiMapPng((fs::path(dir / "gt") / "000000.png").string(), gt_depth);
  WriteKittiMapPng((fs::path(dir / "gt") / "000001.png").string(), gt_depth);
  // Disparity / width: fxb 80 at width 8 -> 10 m needs 8 px = 1.0 of the width.
  cv::Mat good(6, 8, CV_32F, cv::Scalar(1.0f)), bad = good.clone();
  bad.at<float>(4, 3) = std::numeric_limits<float>::quiet_NaN();
  const std::string npy = dir / "pred.npy";
  WriteNpyStack(npy, {good, bad});
  DepthEvalOptions options;
  options.gt_kind = MapKind::kDepth;
  options.fxb = 80.0;
  const std::string split = WriteSplit(dir, 2);
  try {
    EvaluateDepthSplit(split, npy, dir / "gt", options);
    FAIL() << "a NaN prediction was scored";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("pred.npy"), std::string::npos) << what;
    EXPECT_NE(what.find("frame 1"), std::string::npos) << what;
    EXPECT_NE(what.find("x 3, y 4"), std::string::npos) << what;
  }
  const CliRun run = RunDvso("eval-depth --split " + split + " --pred " + npy + " --gt " + dir / "gt" +
                             " --fxb 80 --crop none");
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_NE(run.out.find("pred.npy"), std::string::npos) << run.out;
  // inf too; finite stacks still evaluate (perfect here).
  bad.at<float>(4, 3) = std::numeric_limits<float>::infinity();
  WriteNpyStack(npy, {good, bad});
  EXPECT_THROW(EvaluateDepthSplit(split, npy, dir / "gt", options), Error);
  WriteNpyStack(npy, {good, good});
  EXPECT_NEAR(EvaluateDepthSplit(split, npy, dir / "gt", options).mean.abs_rel, 0.0, 1e-3);
  // The disparity sources' reading is unchanged: a non-finite value is 0 = invalid.
  WriteNpyStack(npy, {good, bad});
  const NpyDisparityStack stack(npy);
  EXPECT_EQ(stack.Frame(1, 8, 6).at<float>(4, 3), 0.0f);
  EXPECT_THROW(stack.Frame(1, 8, 6, NonFiniteDisparity::kError), Error);
  EXPECT_NO_THROW(stack.Frame(0, 8, 6, NonFiniteDisparity::kError));
}

// A 16-bit colour PNG (an image, not a map) was converted to grey and read as a map.
TEST(EvalInputChecks, SixteenBitColourPngIsNotAMap) {
  TempDir dir("eval_png_colour");
  const std::string colour = dir / "colour.png";
  ASSERT_TRUE(cv::imwrite(colour, cv::Mat(4, 5, CV_16UC3, cv::Scalar(256, 512, 1024))));
  try {
    ReadKittiMapPng(colour);
    FAIL() << "a 16-bit colour PNG was read as a map";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("colour.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("3 channel"), std::string::npos) << e.what();
  }
  const std::string grey_alpha = dir / "grey_alpha.png";
  ASSERT_TRUE(cv::imwrite(grey_alpha, cv::Mat(4, 5, CV_16UC4, cv::Scalar(256, 256, 256, 65535))));
  EXPECT_THROW(ReadKittiMapPng(grey_alpha), Error);
  const std::string eight_bit = dir / "eight_bit.png";
  ASSERT_TRUE(cv::imwrite(eight_bit, cv::Mat(4, 5, CV_8U, cv::Scalar(7))));
  EXPECT_THROW(ReadKittiMapPng(eight_bit), Error);
  const std::string map = dir / "map.png";
  ASSERT_TRUE(cv::imwrite(map, cv::Mat(4, 5, CV_16U, cv::Scalar(512))));
  EXPECT_FLOAT_EQ(ReadKittiMapPng(map).at<float>(2, 3), 2.0f);
}

// KITTI rows whose 3x3 block is no rotation, and TUM quaternions of a norm far from 1, are errors naming
// the file and line; printed rotations (KITTI's GT, our writers) and quaternions pass.
TEST(EvalInputChecks, TrajectoryRowsMustHoldRotations) {
  TempDir dir("traj_rotations");
  const auto expect_error = [&](const std::string& name, const std::string& text, const std::string& line) {
    const std::string path = dir / name;
    std::ofstream(path) << text;
    try {
      ReadTrajectory(path);
      ADD_FAILURE() << name << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(line), std::string::npos) << e.what();
    }
  };
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  expect_error("scaled.txt", identity + "3 0 0 0 0 3 0 0 0 0 3 1\n", "line 2: the 3x3 part is not a rotation");
  expect_error("reflection.txt", "1 0 0 0 0 1 0 0 0 0 -1 0\n", "line 1: the 3x3 part is not a rotation");
  expect_error("sheared.txt", "1 0.01 0 0 0 1 0 0 0 0 1 0\n", "line 1");
  expect_error("tiny_q.tum", "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 0.001\n", "line 2: quaternion");
  expect_error("long_q.tum", "0 0 0 0 0 0 0 1.05\n", "line 1: quaternion");
  expect_error("zero_q.tum", "0 0 0 0 0 0 0 0\n", "line 1: quaternion");
  // Within the tolerances: 7-digit rotations (KITTI's GT, every sequence) and slightly rounded quaternions.
  for (int sequence = 0; sequence <= 10; ++sequence) {
    char name[16];
    std::snprintf(name, sizeof(name), "/%02d.txt", sequence);
    EXPECT_NO_THROW(ReadTrajectory(std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses" + name)) << name;
  }
  std::ofstream(dir / "rounded.txt") << "0.9999 0.0001 0 0 -0.0001 1.0001 0 0 0 0 1 0\n";
  EXPECT_NO_THROW(ReadTrajectory(dir / "rounded.txt"));
  std::ofstream(dir / "rounded.tum") << "0 0 0 0 0.7071 0 0 0.7071\n1 0 0 0 0 0 0 1.005\n";
  const Trajectory tum = ReadTrajectory(dir / "rounded.tum");
  EXPECT_NEAR(tum.poses[0].T_world_camera.linear().determinant(), 1.0, 1e-12);  // normalised
  // Through the CLI: one error line naming the file.
  std::ofstream(dir / "gt.txt") << identity << identity;
  const CliRun run = RunDvso("eval-odometry --gt " + dir / "gt.txt" + " --est " + dir / "scaled.txt");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("scaled.txt"), std::string::npos) << run.out;
}

// eval-depth --calib takes fx * baseline of the pair the predictions were made on: the grey pair (P0/P1) by
// default, the colour pair (P2/P3, another baseline on KITTI) with --cameras colour.
TEST(EvalInputChecks, CalibGivesTheFxBOfTheChosenCameraPair) {
  TempDir dir("eval_calib_pair");
  fs::create_directories(dir / "gt");
  fs::create_directories(dir / "pred");
  // Grey: fx 700, baseline 0.5 m (350 px m); colour: fx 700, baseline 0.4 m (280 px m), 0.06 m beside.
  std::ofstream(dir / "calib.txt") << "P0: 700 0 300 0 0 700 100 0 0 0 1 0\n"
                                   << "P1: 700 0 300 -350 0 700 100 0 0 0 1 0\n"
                                   << "P2: 700 0 300 42 0 700 100 0 0 0 1 0\n"
                                   << "P3: 700 0 300 -238 0 700 100 0 0 0 1 0\n";
  // GT depth 20 m; predicted disparity 14 px: 280 / 14 = 20 m on the colour pair, 25 m on the grey one.
  WriteKittiMapPng((fs::path(dir / "gt") / "a.png").string(), cv::Mat(6, 8, CV_32F, cv::Scalar(20.0f)));
  WriteKittiMapPng((fs::path(dir / "pred") / "a.png").string(), cv::Mat(6, 8, CV_32F, cv::Scalar(14.0f)));
  const std::string base = "eval-depth --json --gt-kind depth --pred " + dir / "pred" + " --gt " + dir / "gt" +
                           " --calib " + dir / "calib.txt";
  CliRun run = RunDvso(base + " --cameras colour", /*merge_stderr=*/false);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_NEAR(j["fxb"].get<double>(), 280.0, 1e-9);
  EXPECT_NEAR(j["abs_rel"].get<double>(), 0.0, 1e-3);
  run = RunDvso(base, /*merge_stderr=*/false);  // default: the grey pair
  ASSERT_EQ(run.exit_code, 0) << run.out;
  j = nlohmann::json::parse(run.out);
  EXPECT_NEAR(j["fxb"].get<double>(), 350.0, 1e-9);
  EXPECT_NEAR(j["abs_rel"].get<double>(), 0.25, 1e-3);
  // --cameras means nothing without --calib.
  run = RunDvso("eval-depth --gt-kind depth --pred " + dir / "pred" + " --gt " + dir / "gt" +
                " --fxb 280 --cameras colour");
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.out.find("--calib"), std::string::npos) << run.out;
}

// Depth against depth converts nothing: --split needs no KITTI image width for it, and no fx * baseline is
// reported that was never used.
TEST(EvalInputChecks, SplitDepthAgainstDepthNeedsNoFxB) {
  TempDir dir("eval_split_depth");
  fs::create_directories(dir / "gt");
  fs::create_directories(dir / "pred");
  const cv::Mat gt(6, 8, CV_32F, cv::Scalar(20.0f));  // 8 px wide: no KITTI width
  WriteKittiMapPng((fs::path(dir / "gt") / "000000.png").string(), gt);
  WriteKittiMapPng((fs::path(dir / "pred") / "000000.png").string(), cv::Mat(6, 8, CV_32F, cv::Scalar(25.0f)));
  const std::string split = WriteSplit(dir, 1);
  CliRun run = RunDvso("eval-depth --json --split " + split + " --pred " + dir / "pred" + " --gt " + dir / "gt" +
                           " --pred-kind depth --crop none",
                       /*merge_stderr=*/false);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_NEAR(j["abs_rel"].get<double>(), 0.25, 1e-3);
  EXPECT_FALSE(j.contains("fxb")) << j.dump();
  // The library: the width table is not consulted for depth maps, and an unused fxb is not reported.
  DepthEvalOptions options;
  options.pred_kind = options.gt_kind = MapKind::kDepth;
  options.kitti_focal_by_width = true;
  const DepthEvalResult result = EvaluateDepthSplit(split, dir / "pred", dir / "gt", options);
  EXPECT_FALSE(DepthEvalResultToJson(result, options).contains("fxb"));
  options.kitti_focal_by_width = false;
  options.fxb = 400.0;
  EXPECT_FALSE(DepthEvalResultToJson(result, options).contains("fxb"));
  options.pred_kind = MapKind::kDisparity;
  EXPECT_NEAR(DepthEvalResultToJson(result, options)["fxb"].get<double>(), 400.0, 1e-12);
  // A disparity still needs the width table there (an 8 px image has no KITTI focal length).
  run = RunDvso("eval-depth --split " + split + " --pred " + dir / "pred" + " --gt " + dir / "gt");
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("width 8"), std::string::npos) << run.out;
}

}  // namespace
}  // namespace dvso
