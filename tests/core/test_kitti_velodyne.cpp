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
  const cv::Mat depth = ProjectVelodyneDepth(scan, projection, VelodyneDepthValue::kCameraZ);
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
      testing::RunDvso("gt-depth --quiet --depth-value camera-z --sequence " + drive.string() + " --out " +
                       (tmp.path / "gt").string());
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const cv::Mat png = ReadKittiMapPng((tmp.path / "gt" / "0000000000.png").string());
  for (const auto& [pixel, z] : expected) {
    EXPECT_NEAR(png.at<float>(static_cast<int>(pixel.first), static_cast<int>(pixel.second)), z, 0.5 / 256 + 1e-4);
  }
}

// The default GT value is monodepth's and monodepth2's (generate_depth_map(..., vel_depth=True)): the
// Velodyne forward distance x of the point that hits the pixel, not the camera z (on the KITTI-like rig
// z ~= x - 0.27 m); the nearest point is the one with the smallest x, as monodepth's min over duplicates.
TEST(KittiVelodyne, DefaultDepthValueIsTheVelodyneForwardDistanceAsMonodepth) {
  TempDir tmp("velo_x");
  const testing::RawCalibration calib = testing::WriteRawCalibration(tmp.path);
  const VelodyneProjection projection = ReadVelodyneProjection(tmp.path.string(), 2);
  // Points ahead of the Velodyne, far apart in the image, and one more behind the first on camera 02's ray
  // through it (P_rect_02 = K [I | t]: the ray's points are s (X + t) - t), which the nearer one hides.
  std::vector<VelodynePoint> scan = {{10.0f, 1.0f, -0.5f, 0.5f}, {25.0f, -3.0f, 0.2f, 0.5f},
                                     {6.5f, 0.0f, -1.0f, 0.5f}, {20.0f, -6.0f, -1.0f, 0.5f}};
  const Eigen::Isometry3d rect_from_velo =
      testing::Rigid(calib.rect, Eigen::Vector3d::Zero()) * calib.cam0_from_velo;
  const Eigen::Vector3d t = calib.P_rect_02.leftCols<3>().inverse() * calib.P_rect_02.col(3);
  const Eigen::Vector3d near = rect_from_velo * scan[0].head<3>().cast<double>();
  const Eigen::Vector3f hidden = (rect_from_velo.inverse() * (1.5 * (near + t) - t)).cast<float>();
  scan.emplace_back(hidden.x(), hidden.y(), hidden.z(), 0.5f);
  const cv::Mat x_map = ProjectVelodyneDepth(scan, projection);
  const cv::Mat z_map = ProjectVelodyneDepth(scan, projection, VelodyneDepthValue::kCameraZ);
  EXPECT_EQ(cv::countNonZero(x_map), 4);
  EXPECT_EQ(cv::countNonZero(z_map), 4);
  for (size_t i = 0; i < 4; ++i) {
    const VelodynePoint& p = scan[i];
    const Eigen::Vector3d x = projection.velo_to_image * Eigen::Vector4d(p.x(), p.y(), p.z(), 1.0);
    const int u = static_cast<int>(std::lround(x.x() / x.z())), v = static_cast<int>(std::lround(x.y() / x.z()));
    ASSERT_TRUE(u >= 0 && v >= 0 && u < projection.width && v < projection.height) << i;
    EXPECT_FLOAT_EQ(x_map.at<float>(v, u), p.x()) << i;
    EXPECT_NEAR(z_map.at<float>(v, u), x.z(), 1e-4) << i;
    // The rig puts the Velodyne 0.27 m behind camera 00: the two conventions differ by about that.
    EXPECT_NEAR(p.x() - z_map.at<float>(v, u), 0.27, 0.05) << i;
  }
  EXPECT_THROW(ParseVelodyneDepthValue("depth"), Error);

  // Through the CLI: the default writes x, --depth-value camera-z writes z.
  const fs::path drive = tmp.path / "2011_09_26_drive_0003_sync";
  fs::create_directories(drive / "velodyne_points" / "data");
  WriteVelodyneScan((drive / "velodyne_points" / "data" / "0000000000.bin").string(), scan);
  for (const std::string& value : {std::string(), std::string("camera-z")}) {
    const fs::path out = tmp.path / ("gt" + value);
    const testing::CliRun run = testing::RunDvso("gt-depth --quiet --sequence " + drive.string() + " --out " +
                                                 out.string() + (value.empty() ? "" : " --depth-value " + value));
    ASSERT_EQ(run.exit_code, 0) << run.out;
    const cv::Mat png = ReadKittiMapPng((out / "0000000000.png").string());
    const cv::Mat& expected = value.empty() ? x_map : z_map;
    EXPECT_LE(cv::norm(png, expected, cv::NORM_INF), 0.5 / 256 + 1e-4) << value;
  }
  const testing::CliRun bad = testing::RunDvso("gt-depth --quiet --depth-value z --sequence " + drive.string() +
                                               " --out " + (tmp.path / "bad").string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.out.find("--depth-value"), std::string::npos) << bad.out;
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
