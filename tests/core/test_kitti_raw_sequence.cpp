// KITTI raw drives end to end on drives the simulator writes in the raw layout
// (`dvso simulate --raw-layout sync|extract`, core/kitti_raw_writer.h): the
// raw reader (core/sequence_kitti_raw.cpp) must give the same camera, images
// and times as the KITTI-odometry-layout copy of the same simulation; every
// odometry mode and the labels must give the same result on both; gt-depth
// must give back the simulator's depth at the Velodyne pixels; OXTS poses must
// round-trip; extract drives are rectified on read and paired by timestamp.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/depth_split.h"
#include "core/disparity_io.h"
#include "core/error.h"
#include "core/kitti_raw_writer.h"
#include "core/kitti_velodyne.h"
#include "core/sequence.h"
#include "core/trajectory.h"
#include "tests/dvso_cli_runner.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

constexpr int kFrames = 40;
const char* const kSyncDrive = "kitti_raw/2011_09_26/2011_09_26_drive_0001_sync";
const char* const kExtractDrive = "kitti_raw/2011_09_26/2011_09_26_drive_0001_extract";

TEST(KittiRawSequence, TimestampsAreSecondsSinceTheEpochUtc) {
  EXPECT_NEAR(ParseKittiRawTimestamp("2011-09-26 13:02:25.964389445", "t"), 1317042145.964389445, 1e-6);
  EXPECT_NEAR(ParseKittiRawTimestamp("2011-09-26 13:02:26", "t"), 1317042146.0, 1e-9);
  EXPECT_THROW(ParseKittiRawTimestamp("13:02:25 2011-09-26", "t"), Error);
  EXPECT_EQ(FormatKittiRawTimestamp(1317042146.0), "2011-09-26 13:02:26.000000000");
  // The fraction rounds up into the next minute instead of printing 60 s or 1000000000 ns.
  EXPECT_EQ(FormatKittiRawTimestamp(1317042179.9999999999), "2011-09-26 13:03:00.000000000");
  for (double t : {1317042145.25, 1317042199.1234567, 1317045000.5}) {
    EXPECT_NEAR(ParseKittiRawTimestamp(FormatKittiRawTimestamp(t), "t"), t, 1e-6);
  }
}

// `dvso odometry --mode MODE` of `sequence` into `out` (+ extra arguments): its trajectory, or an empty
// one (and a test failure with the output) when the run fails.
Trajectory Odometry(const std::string& mode, const fs::path& sequence, const fs::path& out,
                    const std::string& extra = "") {
  const testing::CliRun run = testing::RunDvso("odometry --no-progress --mode " + mode + " --sequence " +
                                               sequence.string() + " --out " + out.string() + " " + extra);
  if (run.exit_code != 0) {
    ADD_FAILURE() << run.out;
    return {};
  }
  return ReadTrajectory((out / "trajectory.txt").string());
}

double FinalGap(const Trajectory& a, const Trajectory& b) {
  return (a.poses.back().T_world_camera.translation() - b.poses.back().T_world_camera.translation()).norm();
}

// Copies the simulator's GT disparity maps (%06d.png) under the raw drive's frame names (%010d.png).
fs::path RenamedDisparities(const fs::path& seq, const std::string& sub, const fs::path& out) {
  fs::create_directories(out);
  for (int i = 0; i < kFrames; ++i) {
    char from[32], to[32];
    std::snprintf(from, sizeof(from), "%06d.png", i);
    std::snprintf(to, sizeof(to), "%010d.png", i);
    fs::copy_file(seq / sub / from, out / to, fs::copy_options::overwrite_existing);
  }
  return out;
}

// Every GT pixel of `gt_dir`'s frame `raw_name` equals the simulator's depth (depth_0) within 1 cm; returns
// the number of GT pixels.
int CheckGtDepth(const fs::path& gt_dir, const std::string& raw_name, const fs::path& sim_depth) {
  const cv::Mat gt = ReadKittiMapPng((gt_dir / (raw_name + ".png")).string());
  const cv::Mat sim = ReadKittiMapPng(sim_depth.string());
  EXPECT_EQ(gt.size(), sim.size());
  if (gt.size() != sim.size()) return 0;
  int points = 0;
  double worst = 0.0;
  for (int v = 0; v < gt.rows; ++v) {
    for (int u = 0; u < gt.cols; ++u) {
      const float z = gt.at<float>(v, u);
      if (z <= 0) continue;
      ++points;
      worst = std::max(worst, static_cast<double>(std::abs(z - sim.at<float>(v, u))));
    }
  }
  EXPECT_LT(worst, 0.01) << raw_name;
  return points;
}

// One simulation written in both layouts, shared by the tests below.
class SyncDrive : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(testing::FreshSimulatedSequence("kitti_raw_sync", kFrames, "--color --raw-layout sync"));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override { ASSERT_FALSE(dir_->empty()) << "dvso simulate --raw-layout sync failed"; }
  fs::path Dir() const { return *dir_; }
  fs::path Seq() const { return Dir() / "seq"; }
  fs::path Drive() const { return Seq() / kSyncDrive; }
  // A copy of the drive in a date folder `name` of its own, with the date's calibration files (but for
  // calib_cam_to_cam.txt when a test writes its own): tests change the copy, never the shared drive.
  fs::path CopyOfDrive(const std::string& name, bool with_cam_to_cam = true) const {
    const fs::path copy = Dir() / name / "2011_09_26_drive_0001_sync";
    fs::create_directories(copy.parent_path());
    fs::copy(Drive(), copy, fs::copy_options::recursive);
    for (const char* file : {"calib_cam_to_cam.txt", "calib_velo_to_cam.txt", "calib_imu_to_velo.txt"}) {
      if (with_cam_to_cam || std::string(file) != "calib_cam_to_cam.txt") {
        fs::copy_file(Drive().parent_path() / file, copy.parent_path() / file);
      }
    }
    return copy;
  }
  static std::string* dir_;
};
std::string* SyncDrive::dir_ = nullptr;

TEST_F(SyncDrive, ReadsLikeTheOdometryLayout) {
  const std::unique_ptr<SequenceReader> odometry_layout = OpenSequence(Seq().string());
  const std::unique_ptr<SequenceReader> raw = OpenSequence(Drive().string());
  ASSERT_EQ(raw->size(), odometry_layout->size());
  ASSERT_TRUE(raw->is_stereo());
  ASSERT_TRUE(raw->has_color());
  EXPECT_NEAR(raw->camera().left.fx, odometry_layout->camera().left.fx, 1e-9);
  EXPECT_NEAR(raw->camera().left.cy, odometry_layout->camera().left.cy, 1e-9);
  EXPECT_NEAR(raw->camera().baseline, odometry_layout->camera().baseline, 1e-9);
  EXPECT_EQ(raw->FrameName(7), "0000000007");
  SequenceReadOptions colour;
  colour.load_color = true;
  for (int i : {0, 13, 39}) {
    EXPECT_NEAR(raw->timestamps()[i], odometry_layout->timestamps()[i] - odometry_layout->timestamps()[0], 1e-6);
    const StereoFrame a = raw->Read(i, colour), b = odometry_layout->Read(i, colour);
    EXPECT_EQ(cv::norm(a.left, b.left, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.right, b.right, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.left_color, b.left_color, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.right_color, b.right_color, cv::NORM_INF), 0.0);
  }
  // The colour pair as the sequence: the same camera, grey from colour.
  const std::unique_ptr<SequenceReader> colour_pair = OpenSequence(Drive().string(), "", CameraPair::kColour);
  ASSERT_EQ(colour_pair->size(), raw->size());
  EXPECT_NEAR(colour_pair->camera().baseline, raw->camera().baseline, 1e-9);
  const StereoFrame c = colour_pair->Read(5, colour);
  EXPECT_EQ(c.left.type(), CV_8UC1);
  EXPECT_EQ(c.left_color.type(), CV_8UC3);
  // The odometry layout's colour pair (image_2/image_3, P2/P3) reads the same colour images.
  const std::unique_ptr<SequenceReader> layout_colour = OpenSequence(Seq().string(), "", CameraPair::kColour);
  EXPECT_NEAR(layout_colour->camera().baseline, raw->camera().baseline, 1e-9);
  EXPECT_EQ(cv::norm(layout_colour->Read(5, colour).left_color, c.left_color, cv::NORM_INF), 0.0);
}

TEST_F(SyncDrive, ColourCamerasBesideTheGreyOnesAreNotTheGreyPairsColour) {
  // KITTI's colour cameras sit ~6 cm beside the grey ones: their images are another viewpoint, so the grey
  // pair must not offer them as its colour (a map predicted on them is misplaced on the grey pixels).
  const fs::path copy = CopyOfDrive("colour_beside", /*with_cam_to_cam=*/false);
  std::ifstream in((Drive().parent_path() / "calib_cam_to_cam.txt").string());
  std::ofstream out((copy.parent_path() / "calib_cam_to_cam.txt").string());
  std::string line;
  int moved = 0;
  while (std::getline(in, line)) {
    if (line.rfind("P_rect_02:", 0) == 0 || line.rfind("P_rect_03:", 0) == 0) {
      std::istringstream values(line.substr(10));
      std::vector<double> p(12);
      for (double& v : p) values >> v;
      p[3] += p[0] * 0.06;  // the camera centre 6 cm to the left
      line = line.substr(0, 10);
      for (double v : p) line += " " + std::to_string(v);
      ++moved;
    }
    out << line << "\n";
  }
  out.close();
  ASSERT_EQ(moved, 2);
  SequenceReadOptions colour;
  colour.load_color = true;
  const std::unique_ptr<SequenceReader> grey = OpenSequence(copy.string());
  EXPECT_FALSE(grey->has_color());
  EXPECT_TRUE(grey->Read(3, colour).left_color.empty());
  const std::unique_ptr<SequenceReader> colour_pair = OpenSequence(copy.string(), "", CameraPair::kColour);
  EXPECT_TRUE(colour_pair->has_color());
  EXPECT_FALSE(colour_pair->Read(3, colour).left_color.empty());
  // The unmoved drive offers its colour beside the grey pair (the simulator renders it from the same centres).
  EXPECT_TRUE(OpenSequence(Drive().string())->has_color());
  // With the left colour camera elsewhere, P_rect_03 is never needed by the grey pair: a calibration without
  // it still opens (it is read only when the left colour camera is the grey one).
  const std::string calib = (copy.parent_path() / "calib_cam_to_cam.txt").string();
  std::string kept_lines;
  for (std::ifstream moved_in(calib); std::getline(moved_in, line);) {
    if (line.rfind("P_rect_03:", 0) != 0) kept_lines += line + "\n";
  }
  std::ofstream(calib) << kept_lines;
  ASSERT_TRUE(fs::is_directory(copy / "image_03"));
  EXPECT_FALSE(OpenSequence(copy.string())->has_color());
}

TEST_F(SyncDrive, FrameWithoutItsRightImageIsSkippedNotMispaired) {
  const fs::path copy = CopyOfDrive("gappy");
  fs::remove(copy / "image_01" / "data" / "0000000005.png");
  const std::unique_ptr<SequenceReader> gappy = OpenSequence(copy.string());
  const std::unique_ptr<SequenceReader> odometry_layout = OpenSequence(Seq().string());
  ASSERT_EQ(gappy->size(), kFrames - 1);
  EXPECT_EQ(gappy->FrameName(5), "0000000006");
  EXPECT_EQ(cv::norm(gappy->Read(5).right, odometry_layout->Read(6).right, cv::NORM_INF), 0.0);
  // timestamps.txt keeps its 40 lines: every remaining file keeps the time of its own line.
  EXPECT_NEAR(gappy->timestamps()[5] - gappy->timestamps()[4],
              odometry_layout->timestamps()[6] - odometry_layout->timestamps()[4], 1e-6);
}

// A sync drive's images are rectified to S_rect_0X: images of another size (a resized download beside the
// original calibration) are an error naming the calibration, not a run to a garbage trajectory.
TEST_F(SyncDrive, ImagesOfAnotherSizeThanTheCalibrationAreAnError) {
  const fs::path copy = CopyOfDrive("resized");
  const cv::Size calibrated = OpenSequence(copy.string())->Read(0).left.size();
  for (const auto& entry : fs::directory_iterator(copy / "image_00" / "data")) {
    cv::Mat image = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED), half;
    cv::resize(image, half, calibrated / 2);
    cv::imwrite(entry.path().string(), half);
  }
  try {
    OpenSequence(copy.string());
    FAIL() << "images of half the calibrated size must be an error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("calib_cam_to_cam.txt"), std::string::npos) << what;
    EXPECT_NE(what.find(std::to_string(calibrated.width / 2) + "x" + std::to_string(calibrated.height / 2) + " images"),
              std::string::npos)
        << what;
  }
}

TEST_F(SyncDrive, GtDepthGivesBackTheSimulatedDepthAtTheVelodynePixels) {
  for (int camera : {0, 2}) {
    const fs::path gt = Dir() / ("gt_depth_" + std::to_string(camera));
    // camera-z: the simulator's depth maps hold the camera's z (the default, velodyne-x, is ~0.27 m more).
    const testing::CliRun run =
        testing::RunDvso("gt-depth --quiet --depth-value camera-z --sequence " + Drive().string() + " --out " +
                         gt.string() + " --camera " + std::to_string(camera));
    ASSERT_EQ(run.exit_code, 0) << run.out;
    for (int i : {0, 20, 39}) {
      char raw[32], sim[32];
      std::snprintf(raw, sizeof(raw), "%010d", i);
      std::snprintf(sim, sizeof(sim), "%06d.png", i);
      const int points = CheckGtDepth(gt, raw, Seq() / "depth_0" / sim);
      // Every in-view point has its own pixel; the ground points around the car (behind it, beside the view) fall
      // outside the image or behind the camera and are dropped.
      const std::vector<VelodynePoint> scan =
          ReadVelodyneScan((Drive() / "velodyne_points" / "data" / (std::string(raw) + ".bin")).string());
      int behind = 0;
      for (const VelodynePoint& p : scan) behind += p.x() < 0 ? 1 : 0;
      EXPECT_GT(behind, 1000) << "the scan should see all around the car";
      EXPECT_GT(points, 2000) << raw;
      EXPECT_LT(points, static_cast<int>(scan.size()) - behind);
    }
  }
}

TEST_F(SyncDrive, SplitGtAndEvaluationFollowTheSplitOrder) {
  // Three lines in an order of their own; the right image of frame 20 is evaluated in camera 3.
  const fs::path split = Dir() / "split.txt";
  std::ofstream(split) << "# test split\n2011_09_26/2011_09_26_drive_0001_sync 0000000030 l\n"
                       << "2011_09_26/2011_09_26_drive_0001_sync 0000000020 r\n"
                       << "2011_09_26/2011_09_26_drive_0001_sync 0000000004 l\n";
  const fs::path gt = Dir() / "split_gt";
  testing::CliRun run = testing::RunDvso("gt-depth --quiet --depth-value camera-z --split " + split.string() +
                                         " --raw-root " + (Seq() / "kitti_raw").string() + " --out " + gt.string());
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_GT(CheckGtDepth(gt, "000000", Seq() / "depth_0" / "000030.png"), 2000);
  EXPECT_GT(CheckGtDepth(gt, "000002", Seq() / "depth_0" / "000004.png"), 2000);
  // The r line is frame 20 in camera 3 (one baseline to the right): checked against the simulator's right
  // depth below, through its disparity (disp_1) as a prediction.
  const cv::Mat right = ReadKittiMapPng((gt / "000001.png").string());
  EXPECT_GT(cv::countNonZero(right), 2000);

  // Predictions = the simulator's disparities of each line's camera, as PNGs and as an .npy stack / width.
  const fs::path pred = Dir() / "split_pred";
  fs::create_directories(pred);
  std::vector<cv::Mat> stack;
  const std::vector<std::pair<std::string, std::string>> lines = {
      {"disp_0", "000030.png"}, {"disp_1", "000020.png"}, {"disp_0", "000004.png"}};
  for (size_t i = 0; i < lines.size(); ++i) {
    const cv::Mat disparity = ReadKittiMapPng((Seq() / lines[i].first / lines[i].second).string());
    WriteKittiMapPng((pred / SplitMapName(static_cast<int>(i))).string(), disparity);
    stack.push_back(disparity / disparity.cols);
  }
  WriteNpyStack((Dir() / "split_pred.npy").string(), stack);
  const std::unique_ptr<SequenceReader> sequence = OpenSequence(Seq().string());
  const std::string fxb = std::to_string(sequence->camera().left.fx * sequence->camera().baseline);
  for (const std::string& source : {pred.string(), (Dir() / "split_pred.npy").string()}) {
    run = testing::RunDvso("eval-depth --json --split " + split.string() + " --pred " + source + " --gt " + gt.string() +
                               " --fxb " + fxb,
                           /*merge_stderr=*/false);
    ASSERT_EQ(run.exit_code, 0) << run.out;
    const nlohmann::json result = nlohmann::json::parse(run.out);
    EXPECT_LT(result["abs_rel"].get<double>(), 0.01) << source;
    // The left lines are exact up to quantisation; in camera 3 a few Velodyne points sampled from the left
    // view lie behind foreground the right camera sees in front of them (parallax, as on real KITTI).
    EXPECT_EQ(result["per_image"][0]["a1"].get<double>(), 1.0) << source;
    EXPECT_EQ(result["per_image"][2]["a1"].get<double>(), 1.0) << source;
    EXPECT_GT(result["per_image"][1]["a1"].get<double>(), 0.999) << source;
    EXPECT_EQ(result["crop"].get<std::string>(), "garg") << source;
  }
  // --raw-root: each line's fx * baseline from its drive's calibration (the simulator's colour pair is its grey
  // pair, so the same numbers as --fxb above); without it the width table would not know this image size.
  run = testing::RunDvso("eval-depth --json --split " + split.string() + " --pred " + pred.string() + " --gt " +
                             gt.string() + " --raw-root " + (Seq() / "kitti_raw").string(),
                         /*merge_stderr=*/false);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nlohmann::json per_drive = nlohmann::json::parse(run.out);
  const nlohmann::json with_fxb = nlohmann::json::parse(
      testing::RunDvso("eval-depth --json --split " + split.string() + " --pred " + pred.string() + " --gt " +
                           gt.string() + " --fxb " + fxb, /*merge_stderr=*/false).out);
  EXPECT_NEAR(per_drive["abs_rel"].get<double>(), with_fxb["abs_rel"].get<double>(), 1e-6);
  EXPECT_LT(per_drive["abs_rel"].get<double>(), 0.01);
  EXPECT_NE(testing::RunDvso("eval-depth --split " + split.string() + " --pred " + pred.string() + " --gt " +
                             gt.string()).exit_code, 0) << "no KITTI width: needs --raw-root or --fxb";
  EXPECT_NE(testing::RunDvso("eval-depth --pred " + pred.string() + " --gt " + gt.string() + " --raw-root " +
                             (Seq() / "kitti_raw").string()).exit_code, 0) << "--raw-root needs --split";
  // A stack of the wrong length is refused, naming it.
  WriteNpyStack((Dir() / "short.npy").string(), {stack[0]});
  run = testing::RunDvso("eval-depth --split " + split.string() + " --pred " + (Dir() / "short.npy").string() +
                         " --gt " + gt.string() + " --fxb " + fxb);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.out.find("short.npy"), std::string::npos) << run.out;
}

TEST_F(SyncDrive, OxtsPosesRoundTrip) {
  const fs::path out = Dir() / "oxts_poses.txt";
  const testing::CliRun run =
      testing::RunDvso("oxts-poses --sequence " + Drive().string() + " --out " + out.string() + " --camera 0");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const Trajectory oxts = ReadTrajectory(out.string(), TrajectoryFormat::kKitti);
  const Trajectory gt = ReadTrajectory((Seq() / "poses.txt").string(), TrajectoryFormat::kKitti);
  ASSERT_EQ(oxts.size(), gt.size());
  for (size_t i = 0; i < gt.size(); ++i) {
    const Eigen::Isometry3d error = gt.poses[i].T_world_camera.inverse() * oxts.poses[i].T_world_camera;
    EXPECT_LT(error.translation().norm(), 1e-4) << "frame " << i;
    EXPECT_LT(Eigen::AngleAxisd(error.linear()).angle(), 1e-7) << "frame " << i;
  }
}

TEST_F(SyncDrive, EveryOdometryModeAndTheLabelsMatchTheOdometryLayout) {
  const std::string oracle_raw =
      "--disparity-left " + RenamedDisparities(Seq(), "disp_0", Dir() / "disp_left_raw").string() +
      " --disparity-right " + RenamedDisparities(Seq(), "disp_1", Dir() / "disp_right_raw").string();
  const std::string oracle = "--disparity-left " + (Seq() / "disp_0").string() + " --disparity-right " +
                             (Seq() / "disp_1").string();
  for (const std::string mode : {"stereo", "mono", "dvso"}) {
    const Trajectory a = Odometry(mode, Seq(), Dir() / ("odometry_layout_" + mode), mode == "dvso" ? oracle : "");
    const Trajectory b = Odometry(mode, Drive(), Dir() / ("raw_" + mode), mode == "dvso" ? oracle_raw : "");
    ASSERT_FALSE(a.empty() || b.empty()) << mode;
    ASSERT_EQ(a.size(), b.size()) << mode;
    EXPECT_LT(FinalGap(a, b), 1e-3) << mode;
  }
  const fs::path labels_a = Dir() / "labels_odometry_layout", labels_b = Dir() / "labels_raw";
  for (const auto& [sequence, out] : {std::pair{Seq(), labels_a}, std::pair{Drive(), labels_b}}) {
    const testing::CliRun run = testing::RunDvso("labels --quiet --sequence " + sequence.string() + " --out " + out.string());
    ASSERT_EQ(run.exit_code, 0) << run.out;
  }
  int compared = 0;
  for (const auto& entry : fs::directory_iterator(labels_a)) {
    if (entry.path().extension() != ".png") continue;
    const cv::Mat a = cv::imread(entry.path().string(), cv::IMREAD_UNCHANGED);
    const cv::Mat b = cv::imread((labels_b / entry.path().filename()).string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(b.empty()) << entry.path().filename();
    EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << entry.path().filename();
    ++compared;
  }
  EXPECT_GE(compared, kFrames / 2);
}

TEST_F(SyncDrive, ColourPairRunsTheOdometry) {
  const Trajectory grey = Odometry("stereo", Drive(), Dir() / "grey_pair");
  const Trajectory colour = Odometry("stereo", Drive(), Dir() / "colour_pair", "--cameras colour");
  ASSERT_FALSE(grey.empty() || colour.empty());
  ASSERT_EQ(grey.size(), colour.size());
  EXPECT_LT(FinalGap(grey, colour), 0.02 * grey.PathLength());
  // A layout without colour cameras: a one-line error naming what is missing.
  const fs::path grey_only = Dir() / "grey_only";
  fs::create_directories(grey_only / "image_0");
  fs::copy_file(Seq() / "calib.txt", grey_only / "calib.txt", fs::copy_options::overwrite_existing);
  fs::copy_file(Seq() / "image_0" / "000000.png", grey_only / "image_0" / "000000.png",
                fs::copy_options::overwrite_existing);
  const testing::CliRun wrong = testing::RunDvso("odometry --no-progress --mode stereo --cameras colour --sequence " +
                                                 grey_only.string() + " --out " + (Dir() / "wrong").string());
  EXPECT_NE(wrong.exit_code, 0);
  EXPECT_NE(wrong.out.find("image_2"), std::string::npos) << wrong.out;
}

// A second, shorter grey run into the same drive folder leaves no frame of the first behind (a reader
// would take them for frames of this drive): images, colour cameras, scans and OXTS packets; a folder
// without the simulation's marker is refused.
TEST(KittiRawSequence, ShorterRerunIntoTheSameDriveLeavesNoStaleFrames) {
  const std::string dir = testing::ScratchDir("kitti_raw_rerun");
  const std::string raw = dir + "/raw";
  const std::string common = " --width 160 --height 64 --texture-size 64 --raw-layout sync --raw-out " + raw;
  ASSERT_EQ(testing::RunDvso("simulate --quiet --out " + dir + "/long --count 6 --color" + common).exit_code, 0);
  const fs::path drive = fs::path(raw) / "2011_09_26/2011_09_26_drive_0001_sync";
  ASSERT_TRUE(fs::exists(drive / "image_02/data/0000000005.png")) << drive;
  ASSERT_EQ(testing::RunDvso("simulate --quiet --out " + dir + "/short --count 3" + common).exit_code, 0);
  const auto count = [](const fs::path& folder) {
    if (!fs::is_directory(folder)) return 0;
    return static_cast<int>(std::distance(fs::directory_iterator(folder), fs::directory_iterator()));
  };
  EXPECT_EQ(count(drive / "image_00/data"), 3);
  EXPECT_EQ(count(drive / "image_01/data"), 3);
  EXPECT_FALSE(fs::exists(drive / "image_02")) << "a grey drive with colour folders reads as colour";
  EXPECT_FALSE(fs::exists(drive / "image_03"));
  EXPECT_EQ(count(drive / "velodyne_points/data"), 3);
  EXPECT_EQ(count(drive / "oxts/data"), 3);
  EXPECT_EQ(OpenSequence(drive.string())->size(), 3);
  // A drive folder that no simulation wrote (a real KITTI drive of the same name) is never touched.
  fs::remove(drive / "dvso_simulated_drive.txt");
  const testing::CliRun refused = testing::RunDvso("simulate --quiet --out " + dir + "/again --count 2" + common);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.out.find("not written by `dvso simulate`"), std::string::npos) << refused.out;
  EXPECT_FALSE(fs::exists(dir + "/again/image_0")) << "refused before rendering";
  EXPECT_EQ(count(drive / "image_00/data"), 3);
}

// The date folder's calibration files are read by every drive of the date: a simulation never replaces
// them under another drive (a real KITTI date folder with only its calibration and other drives, or an
// earlier simulated drive of another camera); the same camera can share them, and a rerun of the only
// drive may change them.
TEST(KittiRawSequence, CalibrationOfTheDateFolderIsNeverChangedUnderAnotherDrive) {
  const std::string dir = testing::ScratchDir("kitti_raw_calibration");
  const std::string raw = dir + "/raw";
  const std::string common = " --quiet --count 2 --width 160 --height 64 --texture-size 64 --raw-layout sync";
  const fs::path date = fs::path(raw) / "2011_09_26";
  const auto read = [](const fs::path& path) {
    std::ifstream in(path);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  // A "real" date folder: its own calibration and a drive without the simulation's marker.
  fs::create_directories(date / "2011_09_26_drive_0002_sync/image_00/data");
  std::ofstream(date / "calib_cam_to_cam.txt") << "calib_time: 09-Jan-2012 13:57:47\nP_rect_00: 721.5 0 609.6 0 0 "
                                                  "721.5 172.9 0 0 0 1 0\n";
  const std::string real = read(date / "calib_cam_to_cam.txt");
  const testing::CliRun refused = testing::RunDvso("simulate --out " + dir + "/a --raw-out " + raw + common);
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.out.find("2011_09_26_drive_0002_sync"), std::string::npos) << refused.out;
  EXPECT_NE(refused.out.find("calib_cam_to_cam.txt"), std::string::npos) << refused.out;
  EXPECT_EQ(read(date / "calib_cam_to_cam.txt"), real);
  EXPECT_FALSE(fs::exists(dir + "/a/image_0")) << "refused before rendering";

  // Simulated drives only: a second drive of the same camera shares the calibration, one of another
  // camera (baseline) is refused, and the first drive's calibration stays.
  const std::string sim_root = dir + "/sim";
  ASSERT_EQ(testing::RunDvso("simulate --out " + dir + "/b --raw-out " + sim_root + common).exit_code, 0);
  const fs::path sim_date = fs::path(sim_root) / "2011_09_26";
  const std::string first = read(sim_date / "calib_cam_to_cam.txt");
  EXPECT_EQ(testing::RunDvso("simulate --out " + dir + "/c --seed 5 --raw-drive 2 --raw-out " + sim_root + common)
                .exit_code, 0);
  EXPECT_TRUE(fs::exists(sim_date / "2011_09_26_drive_0002_sync" / "image_00/data/0000000001.png"));
  const testing::CliRun other_camera = testing::RunDvso("simulate --out " + dir + "/d --baseline 0.3 --raw-drive 3 "
                                                        "--raw-out " + sim_root + common);
  EXPECT_NE(other_camera.exit_code, 0);
  EXPECT_NE(other_camera.out.find("2011_09_26_drive_0001_sync"), std::string::npos) << other_camera.out;
  EXPECT_FALSE(fs::exists(dir + "/d/image_0")) << "refused before rendering";
  EXPECT_EQ(read(sim_date / "calib_cam_to_cam.txt"), first);
  // The only drive of a date, rerun with another camera, takes its calibration along.
  const std::string alone = dir + "/alone";
  ASSERT_EQ(testing::RunDvso("simulate --out " + dir + "/e --raw-out " + alone + common).exit_code, 0);
  const std::string before = read(fs::path(alone) / "2011_09_26/calib_cam_to_cam.txt");
  ASSERT_EQ(testing::RunDvso("simulate --out " + dir + "/f --baseline 0.3 --raw-out " + alone + common).exit_code, 0);
  EXPECT_NE(read(fs::path(alone) / "2011_09_26/calib_cam_to_cam.txt"), before);
}

// velodyne_max_range limits the range from the scanner, as on the HDL-64E, not the camera depth (which
// let in-view points at the image edges reach ~1.3x the limit).
TEST(KittiRawSequence, SyntheticScanKeepsEveryPointWithinTheScannersRange) {
  const std::string dir = testing::FreshSimulatedSequence("kitti_raw_range", 2);
  ASSERT_FALSE(dir.empty());
  KittiRawDriveOptions options;
  options.velodyne_max_range = 12.0;
  const KittiRawDriveSummary summary = WriteKittiRawDrive(dir + "/seq", dir + "/raw", options);
  const std::vector<VelodynePoint> scan =
      ReadVelodyneScan((fs::path(summary.drive_dir) / "velodyne_points/data/0000000001.bin").string());
  ASSERT_GT(scan.size(), 100u);
  double farthest = 0.0;
  for (const VelodynePoint& p : scan) farthest = std::max(farthest, static_cast<double>(p.head<3>().norm()));
  EXPECT_LT(farthest, options.velodyne_max_range);
  EXPECT_GT(farthest, 0.8 * options.velodyne_max_range);  // the limit, not something nearer, cuts the scan
}

TEST(KittiRawSequence, ExtractDriveIsRectifiedOnReadAndPairedByTimestamp) {
  // The right cameras lose every 9th frame (9, 18, 27, 36).
  const std::string dir_name = testing::FreshSimulatedSequence(
      "kitti_raw_extract", kFrames, "--color --raw-layout extract --raw-drop-every 9");
  ASSERT_FALSE(dir_name.empty());
  const fs::path seq = fs::path(dir_name) / "seq", drive = seq / kExtractDrive;
  const std::unique_ptr<SequenceReader> odometry_layout = OpenSequence(seq.string());
  const std::unique_ptr<SequenceReader> raw = OpenSequence(drive.string());
  ASSERT_EQ(raw->size(), kFrames - 4);
  EXPECT_EQ(raw->FrameName(9), "0000000010");
  ASSERT_TRUE(raw->has_color());
  // The raw files are larger than the rectified images (distorted, unrectified).
  const cv::Mat raw_file = cv::imread((drive / "image_00" / "data" / "0000000020.png").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(raw_file.empty());
  EXPECT_GT(raw_file.cols, odometry_layout->camera().left.width);

  // Rectified on read: the interior matches the original rectified images (two interpolations apart); the
  // right image of each frame is the right camera's own file of the same time despite the shifted numbering.
  SequenceReadOptions colour;
  colour.load_color = true;
  const std::vector<std::pair<int, int>> frames = {{0, 0}, {9, 10}, {17, 19}, {35, 39}};  // (reader, simulation)
  for (const auto& [i, original] : frames) {
    const StereoFrame a = raw->Read(i, colour), b = odometry_layout->Read(original, colour);
    const cv::Rect interior(20, 10, a.left.cols - 40, a.left.rows - 20);
    for (const auto& [x, y] : {std::pair{a.left, b.left}, std::pair{a.right, b.right}, std::pair{a.left_color, b.left_color},
                               std::pair{a.right_color, b.right_color}}) {
      ASSERT_EQ(x.size(), y.size());
      cv::Mat diff;
      cv::absdiff(x(interior), y(interior), diff);
      EXPECT_LT(cv::mean(diff)[0], 4.0) << "frame " << i;
    }
  }

  // Stereo odometry on the extract drive stays close to the one on the rectified sequence.
  const Trajectory a = Odometry("stereo", seq, fs::path(dir_name) / "out_odometry");
  const Trajectory b = Odometry("stereo", drive, fs::path(dir_name) / "out_raw");
  ASSERT_FALSE(a.empty() || b.empty());
  ASSERT_EQ(b.size() + 4, a.size());
  EXPECT_LT(FinalGap(a, b), 0.02 * a.PathLength()) << "over " << a.PathLength() << " m";

  // OXTS poses: one line per kept frame (the drive has a packet for every frame), so they match the
  // trajectory line by line; line 9 is simulation frame 10.
  const fs::path oxts_path = fs::path(dir_name) / "oxts_poses.txt";
  const testing::CliRun oxts_run =
      testing::RunDvso("oxts-poses --sequence " + drive.string() + " --out " + oxts_path.string());
  ASSERT_EQ(oxts_run.exit_code, 0) << oxts_run.out;
  const Trajectory oxts = ReadTrajectory(oxts_path.string(), TrajectoryFormat::kKitti);
  const Trajectory gt_poses = ReadTrajectory((seq / "poses.txt").string(), TrajectoryFormat::kKitti);
  ASSERT_EQ(oxts.size(), b.size());
  for (const auto& [line, frame] : frames) {
    const Eigen::Isometry3d error = gt_poses.poses[frame].T_world_camera.inverse() * oxts.poses[line].T_world_camera;
    EXPECT_LT(error.translation().norm(), 1e-4) << "line " << line;
  }
  // The right camera (its own file numbers shifted by the drops) through a drive path with a trailing
  // slash: frames are timed by the left camera's timestamps, the drive is still an extract drive and
  // its calibration is in the date folder above it.
  const fs::path right_path = fs::path(dir_name) / "oxts_poses_right.txt";
  const testing::CliRun right_run = testing::RunDvso("oxts-poses --camera 1 --sequence " + drive.string() +
                                                     "/ --out " + right_path.string());
  ASSERT_EQ(right_run.exit_code, 0) << right_run.out;
  const Trajectory right = ReadTrajectory(right_path.string(), TrajectoryFormat::kKitti);
  ASSERT_EQ(right.size(), b.size());
  Eigen::Isometry3d left_from_right = Eigen::Isometry3d::Identity();
  left_from_right.translation().x() = odometry_layout->camera().baseline;
  for (const auto& [line, frame] : frames) {
    const Eigen::Isometry3d expected = left_from_right.inverse() * gt_poses.poses[frame].T_world_camera * left_from_right;
    EXPECT_LT((expected.inverse() * right.poses[line].T_world_camera).translation().norm(), 1e-4) << "line " << line;
  }

  // Text Velodyne scans (the extract format) give the same depth GT.
  const fs::path gt = fs::path(dir_name) / "gt_depth";
  const testing::CliRun run =
      testing::RunDvso("gt-depth --quiet --depth-value camera-z --sequence " + drive.string() + " --out " +
                       gt.string());
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_TRUE(fs::exists(drive / "velodyne_points" / "data" / "0000000011.txt"));
  EXPECT_GT(CheckGtDepth(gt, "0000000011", seq / "depth_0" / "000011.png"), 2000);
}

}  // namespace
}  // namespace dvso
