// Velodyne depth GT (core/kitti_velodyne.h, `dvso gt-depth`): a constructed
// scan (a wall, a nearer box in front of part of it, points behind the car)
// projected with KITTI-like calibration; every depth is checked against the
// projection computed by hand from P_rect_02 and the points' rectified coordinates.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/kitti_velodyne.h"
#include "tests/core/kitti_raw_test_util.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

using testing::TempDir;

TEST(KittiVelodyne, ScanProjectsToTheNearestDepthPerPixelLikeTheHandProjection) {
  TempDir tmp("velo_scan");
  const testing::RawCalibration calib = testing::WriteRawCalibration(tmp.path);
  // Points in rectified camera-00 coordinates: a wall at z = 20 m, a box face at z = 8 m in front of
  // part of it, and points behind the car (z < 0) that must not appear.
  std::vector<Eigen::Vector3d> rectified;
  for (double x = -8; x <= 8; x += 0.05)
    for (double y = -2; y <= 1.5; y += 0.1) rectified.emplace_back(x, y, 20.0);
  for (double x = -1; x <= 1; x += 0.02)
    for (double y = -0.5; y <= 1.0; y += 0.05) rectified.emplace_back(x, y, 8.0);
  for (double x = -5; x <= 5; x += 0.5) rectified.emplace_back(x, 0.5, -6.0);
  const Eigen::Isometry3d velo_from_rectified =
      (testing::Rigid(calib.rect, Eigen::Vector3d::Zero()) * calib.cam0_from_velo).inverse();
  std::vector<VelodynePoint> scan;
  for (const Eigen::Vector3d& p : rectified) {
    const Eigen::Vector3f v = (velo_from_rectified * p).cast<float>();
    scan.emplace_back(v.x(), v.y(), v.z(), 0.5f);
  }
  // Expected: hand projection with P_rect_02 of the float-rounded points, nearest per pixel.
  std::map<std::pair<long, long>, double> expected;
  for (const VelodynePoint& v : scan) {
    const Eigen::Vector3d r = velo_from_rectified.inverse() * v.head<3>().cast<double>();
    const Eigen::Vector3d x = calib.P_rect_02 * r.homogeneous();
    if (r.z() <= 0) continue;
    const std::pair<long, long> pixel{std::lround(x.y() / x.z()), std::lround(x.x() / x.z())};
    if (pixel.first < 0 || pixel.second < 0 || pixel.first >= 375 || pixel.second >= 1242) continue;
    auto [it, inserted] = expected.emplace(pixel, x.z());
    if (!inserted) it->second = std::min(it->second, x.z());
  }
  ASSERT_GT(expected.size(), 1000u);

  const VelodyneProjection projection = ReadVelodyneProjection(tmp.path.string(), 2);
  ASSERT_EQ(projection.width, 1242);
  ASSERT_EQ(projection.height, 375);
  const cv::Mat depth = ProjectVelodyneDepth(scan, projection);
  EXPECT_EQ(cv::countNonZero(depth), static_cast<int>(expected.size()));
  int near_pixels = 0;
  for (const auto& [pixel, z] : expected) {
    EXPECT_NEAR(depth.at<float>(static_cast<int>(pixel.first), static_cast<int>(pixel.second)), z, 1e-4);
    near_pixels += z < 10;
  }
  EXPECT_GT(near_pixels, 100);  // the box hides the wall where both project

  // Through the CLI: a raw drive folder, PNG depth (m * 256) within half a quantisation step.
  const fs::path drive = tmp.path / "2011_09_26_drive_0002_sync";
  fs::create_directories(drive / "velodyne_points" / "data");
  WriteVelodyneScan((drive / "velodyne_points" / "data" / "0000000000.bin").string(), scan);
  EXPECT_EQ(ReadVelodyneScan((drive / "velodyne_points" / "data" / "0000000000.bin").string()).size(), scan.size());
  {  // The extract drives' text format gives the same points.
    std::ofstream text(tmp.path / "scan.txt");
    text.precision(9);
    for (const VelodynePoint& p : scan) text << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << p.w() << '\n';
  }
  const std::vector<VelodynePoint> from_text = ReadVelodyneScan((tmp.path / "scan.txt").string());
  ASSERT_EQ(from_text.size(), scan.size());
  EXPECT_TRUE(from_text[17].isApprox(scan[17], 1e-6f));
  const testing::CliRun run =
      testing::RunDvso("gt-depth --quiet --sequence " + drive.string() + " --out " + (tmp.path / "gt").string());
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const cv::Mat png = ReadKittiMapPng((tmp.path / "gt" / "0000000000.png").string());
  for (const auto& [pixel, z] : expected) {
    EXPECT_NEAR(png.at<float>(static_cast<int>(pixel.first), static_cast<int>(pixel.second)), z, 0.5 / 256 + 1e-4);
  }
}

TEST(KittiVelodyne, BadScanIsOneClearError) {
  TempDir tmp("velo_bad");
  const std::string path = (tmp.path / "0000000000.bin").string();
  std::ofstream(path, std::ios::binary) << "0123456789";  // 10 bytes: not whole points
  try {
    ReadVelodyneScan(path);
    FAIL() << "a truncated scan must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("0000000000.bin"), std::string::npos) << e.what();
  }
  std::ofstream(tmp.path / "bad.txt") << "1 2 3 0.5\n4 5 six 0.5\n";
  try {
    ReadVelodyneScan((tmp.path / "bad.txt").string());
    FAIL() << "a malformed text scan must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
  }
  const testing::CliRun run = testing::RunDvso("gt-depth --sequence " + tmp.path.string() + " --out " +
                                               (tmp.path / "gt").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("velodyne_points"), std::string::npos) << run.out;
}

// Options of the other mode (a drive vs a split file) are errors, not silently ignored.
TEST(KittiVelodyne, GtDepthRefusesOptionsOfTheOtherMode) {
  TempDir tmp("velo_options");
  const std::string out = " --out " + (tmp.path / "gt").string();
  testing::CliRun run = testing::RunDvso("gt-depth --split s.txt --raw-root r --camera 0" + out);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.out.find("--camera"), std::string::npos) << run.out;
  run = testing::RunDvso("gt-depth --sequence " + tmp.path.string() + " --raw-root r" + out);
  EXPECT_NE(run.exit_code, 0);
  EXPECT_NE(run.out.find("--raw-root"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(tmp.path / "gt"));
}

}  // namespace
}  // namespace dvso
