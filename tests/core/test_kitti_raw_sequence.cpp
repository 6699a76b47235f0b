// KITTI raw rectified drive reader (core/sequence_kitti_raw.cpp): a simulated
// KITTI-odometry-layout sequence rewritten in the raw layout (date folder with
// calib_cam_to_cam.txt, DRIVE/image_0X/data/%010d.png, timestamps.txt) must
// read back as the same camera, images and times, and stereo odometry on it
// must give the same trajectory; a frame missing in the right camera is
// skipped, not paired with a neighbour.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/sequence.h"
#include "core/trajectory.h"
#include "tests/dvso_cli_runner.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

TEST(KittiRawSequence, TimestampsAreSecondsSinceTheEpochUtc) {
  EXPECT_NEAR(ParseKittiRawTimestamp("2011-09-26 13:02:25.964389445", "t"), 1317042145.964389445, 1e-6);
  EXPECT_NEAR(ParseKittiRawTimestamp("2011-09-26 13:02:26", "t"), 1317042146.0, 1e-9);
  EXPECT_THROW(ParseKittiRawTimestamp("13:02:25 2011-09-26", "t"), Error);
}

std::string RawName(int i, const char* ext) {
  char name[32];
  std::snprintf(name, sizeof(name), "%010d%s", i, ext);
  return name;
}

// Rewrites `seq` (KITTI odometry layout, grey pair) as date_dir/2011_09_26_drive_0001_sync.
fs::path WriteAsRawDrive(const fs::path& seq, const fs::path& date_dir) {
  const fs::path drive = date_dir / "2011_09_26_drive_0001_sync";
  const std::unique_ptr<SequenceReader> reader = OpenSequence(seq.string());
  const StereoCamera& cam = reader->camera();
  std::ofstream calib(date_dir / "calib_cam_to_cam.txt");
  calib.precision(17);
  calib << "calib_time: 09-Jan-2012 13:57:47\nS_rect_00: " << cam.left.width << " " << cam.left.height
        << "\nP_rect_00: " << cam.left.fx << " 0 " << cam.left.cx << " 0 0 " << cam.left.fy << " " << cam.left.cy
        << " 0 0 0 1 0\nP_rect_01: " << cam.left.fx << " 0 " << cam.left.cx << " " << -cam.left.fx * cam.baseline
        << " 0 " << cam.left.fy << " " << cam.left.cy << " 0 0 0 1 0\n";
  for (const char* id : {"00", "01"}) {
    fs::create_directories(drive / ("image_" + std::string(id)) / "data");
    std::ofstream times(drive / ("image_" + std::string(id)) / "timestamps.txt");
    for (int i = 0; i < reader->size(); ++i) {
      const double t = reader->timestamps()[i];
      char stamp[64];
      std::snprintf(stamp, sizeof(stamp), "2011-09-26 13:02:%02d.%09d", 10 + static_cast<int>(t),
                    static_cast<int>(std::lround((t - std::floor(t)) * 1e9)));
      times << stamp << "\n";
      const fs::path from = seq / (id == std::string("00") ? "image_0" : "image_1") / (reader->FrameName(i) + ".png");
      fs::copy_file(from, drive / ("image_" + std::string(id)) / "data" / RawName(i, ".png"));
    }
  }
  return drive;
}

TEST(KittiRawSequence, RawDriveReadsAndRunsLikeTheOdometryLayout) {
  const std::string dir = testing::FreshSimulatedSequence("kitti_raw_sequence", 40);
  ASSERT_FALSE(dir.empty());
  const fs::path seq = fs::path(dir) / "seq";
  const fs::path drive = WriteAsRawDrive(seq, fs::path(dir));

  const std::unique_ptr<SequenceReader> odometry_layout = OpenSequence(seq.string());
  const std::unique_ptr<SequenceReader> raw = OpenSequence(drive.string());
  ASSERT_EQ(raw->size(), odometry_layout->size());
  ASSERT_TRUE(raw->is_stereo());
  EXPECT_NEAR(raw->camera().left.fx, odometry_layout->camera().left.fx, 1e-9);
  EXPECT_NEAR(raw->camera().left.cy, odometry_layout->camera().left.cy, 1e-9);
  EXPECT_NEAR(raw->camera().baseline, odometry_layout->camera().baseline, 1e-9);
  EXPECT_EQ(raw->FrameName(7), "0000000007");
  for (int i : {0, 13, 39}) {
    EXPECT_NEAR(raw->timestamps()[i], odometry_layout->timestamps()[i] - odometry_layout->timestamps()[0], 1e-6);
    const StereoFrame a = raw->Read(i), b = odometry_layout->Read(i);
    EXPECT_EQ(cv::norm(a.left, b.left, cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.right, b.right, cv::NORM_INF), 0.0);
  }

  // Stereo odometry on both layouts: the same trajectory.
  for (const auto& [input, out] : {std::pair{seq, fs::path(dir) / "out_odometry"}, {drive, fs::path(dir) / "out_raw"}}) {
    const testing::CliRun run =
        testing::RunDvso("odometry --no-progress --mode stereo --sequence " + input.string() + " --out " + out.string());
    ASSERT_EQ(run.exit_code, 0) << run.out;
  }
  const Trajectory a = ReadTrajectory((fs::path(dir) / "out_odometry" / "trajectory.txt").string());
  const Trajectory b = ReadTrajectory((fs::path(dir) / "out_raw" / "trajectory.txt").string());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LT((a.poses.back().T_world_camera.translation() - b.poses.back().T_world_camera.translation()).norm(), 1e-3);

  // A frame without its right image is skipped, and the rest stay paired by name.
  fs::remove(drive / "image_01" / "data" / RawName(5, ".png"));
  const std::unique_ptr<SequenceReader> gappy = OpenSequence(drive.string());
  ASSERT_EQ(gappy->size(), odometry_layout->size() - 1);
  EXPECT_EQ(gappy->FrameName(5), "0000000006");
  EXPECT_EQ(cv::norm(gappy->Read(5).right, odometry_layout->Read(6).right, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace dvso
