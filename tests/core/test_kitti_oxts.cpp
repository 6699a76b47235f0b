// OXTS -> camera poses (core/kitti_oxts.h): the devkit's Mercator formulas by
// hand, the packet <-> pose round trip, and a synthetic raw drive (calibration
// files in the date folder, packets written from known camera poses) read back
// through the library and through `dvso oxts-poses`.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include "core/error.h"
#include "core/kitti_oxts.h"
#include "core/trajectory.h"
#include "tests/core/kitti_raw_test_util.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

using testing::TempDir;

TEST(KittiOxts, MercatorFormulasByHand) {
  EXPECT_DOUBLE_EQ(MercatorScale(0.0), 1.0);
  EXPECT_NEAR(MercatorScale(60.0), 0.5, 1e-12);
  OxtsPacket p;
  p.lon = 1.0;  // one degree of longitude on the equator: pi * r / 180
  p.alt = 5.0;
  p.yaw = M_PI / 2;
  const Eigen::Isometry3d T = OxtsToPose(p, 1.0);
  EXPECT_NEAR(T.translation().x(), 111319.490793, 1e-5);
  EXPECT_NEAR(T.translation().y(), 0.0, 1e-9);  // ln(tan(45 deg)) = 0
  EXPECT_DOUBLE_EQ(T.translation().z(), 5.0);
  EXPECT_TRUE(T.linear().col(0).isApprox(Eigen::Vector3d::UnitY(), 1e-12));  // yaw 90 deg: x forward -> y
  // Latitude 45 deg at scale 0.5: y = 0.5 r ln(tan(67.5 deg)).
  p = OxtsPacket{};
  p.lat = 45.0;
  EXPECT_NEAR(OxtsToPose(p, 0.5).translation().y(), 0.5 * kEarthRadius * std::log(std::tan(67.5 * M_PI / 180)), 1e-6);
}

TEST(KittiOxts, PacketPoseRoundTrip) {
  const double scale = MercatorScale(49.0);
  for (const auto& angles : {Eigen::Vector3d(0.01, -0.02, 1.3), Eigen::Vector3d(-0.2, 0.4, -2.9),
                             Eigen::Vector3d(0.0, 0.0, 0.0)}) {
    OxtsPacket p;
    p.lat = 49.0112, p.lon = 8.4173, p.alt = 115.3, p.roll = angles.x(), p.pitch = angles.y(), p.yaw = angles.z();
    const OxtsPacket q = PoseToOxts(OxtsToPose(p, scale), scale);
    EXPECT_NEAR(q.lat, p.lat, 1e-10);
    EXPECT_NEAR(q.lon, p.lon, 1e-10);
    EXPECT_NEAR(q.alt, p.alt, 1e-9);
    EXPECT_NEAR(q.roll, p.roll, 1e-12);
    EXPECT_NEAR(q.pitch, p.pitch, 1e-12);
    EXPECT_NEAR(q.yaw, p.yaw, 1e-12);
  }
}

// T_camrect2_imu of the calibration written by WriteRawCalibration, composed by hand.
Eigen::Isometry3d CameraTwoFromImu(const testing::RawCalibration& c) {
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = c.camera2_offset;
  return shift * testing::Rigid(c.rect, Eigen::Vector3d::Zero()) * c.cam0_from_velo * c.velo_from_imu;
}

TEST(KittiOxts, SyntheticDriveRoundTripsThroughCalibrationAndCli) {
  TempDir tmp("oxts_drive");
  const fs::path drive = tmp.path / "2011_09_26_drive_0001_sync";
  fs::create_directories(drive / "oxts" / "data");
  const Eigen::Isometry3d camera_from_imu = CameraTwoFromImu(testing::WriteRawCalibration(tmp.path));
  EXPECT_TRUE(CameraFromImu(tmp.path.string(), 2).isApprox(camera_from_imu, 1e-12));

  // Camera 02 moves forward 1 m per frame while turning and bobbing; the world is placed at
  // Karlsruhe (lat 49.01, lon 8.42) in the Mercator frame of the first packet's scale.
  const double scale = MercatorScale(49.01);
  OxtsPacket origin;
  origin.lat = 49.01, origin.lon = 8.42, origin.alt = 115.0, origin.yaw = 0.7;
  // Camera frame (y down, z forward) -> IMU-like world axes (z up) for the first camera.
  Eigen::Matrix3d cam_to_up;
  cam_to_up << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Isometry3d mercator_from_world = OxtsToPose(origin, scale) * testing::Rigid(cam_to_up, Eigen::Vector3d::Zero());
  std::vector<Eigen::Isometry3d> world_from_camera;
  constexpr int kFrames = 40;
  for (int i = 0; i < kFrames; ++i) {
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.02 * i, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(0.01 * std::sin(0.3 * i), Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    world_from_camera.push_back(testing::Rigid(R, {5.0 * std::sin(0.02 * i), 0.05 * std::sin(0.5 * i), 1.0 * i}));
    const Eigen::Isometry3d mercator_from_imu = mercator_from_world * world_from_camera.back() * camera_from_imu;
    char name[32];
    std::snprintf(name, sizeof(name), "%010d.txt", i);
    WriteOxtsPacket((drive / "oxts" / "data" / name).string(), PoseToOxts(mercator_from_imu, scale));
  }

  const std::map<long long, Eigen::Isometry3d> poses = OxtsCameraPoses(drive.string(), 2);
  ASSERT_EQ(poses.size(), static_cast<size_t>(kFrames));
  double worst = 0.0;
  for (int i = 0; i < kFrames; ++i) {
    const Eigen::Isometry3d expected = world_from_camera[0].inverse() * world_from_camera[i];
    worst = std::max(worst, (poses.at(i).translation() - expected.translation()).norm());
    EXPECT_TRUE(poses.at(i).linear().isApprox(expected.linear(), 1e-9)) << "frame " << i;
  }
  EXPECT_LT(worst, 1e-5) << "m";  // ~4e-6 m: atan(exp(y / r)) of a y of ~5.6e6 m in doubles
  // Camera 00 differs from 02 by the rectified baseline offset only (0.06 m along x).
  const std::map<long long, Eigen::Isometry3d> grey = OxtsCameraPoses(drive.string(), 0);
  EXPECT_NEAR((grey.at(10).translation() - poses.at(10).translation()).norm(), 0.0, 0.2);
  EXPECT_GT((grey.at(10).translation() - poses.at(10).translation()).norm(), 1e-4);

  // The CLI writes the same poses as a KITTI file.
  const std::string out = (tmp.path / "poses.txt").string();
  const testing::CliRun run = testing::RunDvso("oxts-poses --sequence " + drive.string() + " --camera 2 --out " + out);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const Trajectory written = ReadTrajectory(out);
  ASSERT_EQ(written.size(), static_cast<size_t>(kFrames));
  EXPECT_LT((written.poses[kFrames - 1].T_world_camera.translation() - poses.at(kFrames - 1).translation()).norm(),
            1e-9);

  // A missing packet keeps the others on their own frame numbers; without images (one line per packet) it is
  // an error naming it, since every later line would otherwise hold the next frame's pose.
  fs::remove(drive / "oxts" / "data" / "0000000005.txt");
  const std::map<long long, Eigen::Isometry3d> gappy = OxtsCameraPoses(drive.string(), 2);
  ASSERT_EQ(gappy.size(), static_cast<size_t>(kFrames - 1));
  EXPECT_EQ(gappy.count(5), 0u);
  EXPECT_LT((gappy.at(6).translation() - poses.at(6).translation()).norm(), 1e-9);
  const testing::CliRun gap_run =
      testing::RunDvso("oxts-poses --sequence " + drive.string() + " --camera 2 --out " + out);
  EXPECT_EQ(gap_run.exit_code, 1);
  EXPECT_NE(gap_run.out.find("0000000005.txt"), std::string::npos) << gap_run.out;
}

// A damaged sync download: frame 5 gone from every camera and from oxts/data. The frames keep their file
// numbers, so frame 6's line holds packet 6's pose, not packet 7's (the position in the packet list would
// shift every later pose); a kept frame whose packet is missing is an error naming the packet.
TEST(KittiOxts, SyncDrivePacketsAreTakenByFrameNumber) {
  const std::string dir = testing::FreshSimulatedSequence("oxts_gap", 12, "--color --raw-layout sync");
  ASSERT_FALSE(dir.empty()) << "dvso simulate --raw-layout sync failed";
  const fs::path seq = fs::path(dir) / "seq";
  const fs::path drive = seq / "kitti_raw" / "2011_09_26" / "2011_09_26_drive_0001_sync";
  ASSERT_TRUE(fs::is_directory(drive / "oxts" / "data"));
  for (const char* camera : {"image_00", "image_01", "image_02", "image_03"}) {
    fs::remove(drive / camera / "data" / "0000000005.png");
  }
  fs::remove(drive / "oxts" / "data" / "0000000005.txt");
  const fs::path out = fs::path(dir) / "oxts_poses.txt";
  testing::CliRun run = testing::RunDvso("oxts-poses --sequence " + drive.string() + " --camera 0 --out " +
                                         out.string());
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const Trajectory oxts = ReadTrajectory(out.string(), TrajectoryFormat::kKitti);
  const Trajectory gt = ReadTrajectory((seq / "poses.txt").string(), TrajectoryFormat::kKitti);
  ASSERT_EQ(oxts.size(), 11u);
  for (size_t line = 0; line < oxts.size(); ++line) {
    const size_t frame = line < 5 ? line : line + 1;
    const Eigen::Isometry3d error = gt.poses[frame].T_world_camera.inverse() * oxts.poses[line].T_world_camera;
    EXPECT_LT(error.translation().norm(), 1e-4) << "line " << line << ", frame " << frame;
  }
  // Frame 8 keeps its images but loses its packet: an error naming the packet, not a shifted pose.
  fs::remove(drive / "oxts" / "data" / "0000000008.txt");
  run = testing::RunDvso("oxts-poses --sequence " + drive.string() + " --camera 0 --out " + out.string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("0000000008.txt"), std::string::npos) << run.out;
}

TEST(KittiOxts, NearestTimestampNeedsNoSortedTimes) {
  // Real OXTS timestamps jump back now and then: the nearest is searched over all of them.
  const std::vector<double> times = {10.00, 10.01, 10.02, 9.50, 10.03, 10.04};
  EXPECT_EQ(NearestTimestamp(times, 10.012), 1u);
  EXPECT_EQ(NearestTimestamp(times, 9.6), 3u);
  EXPECT_EQ(NearestTimestamp({1.0, 2.0, 3.0}, 2.5), 1u);  // a tie: the first
  EXPECT_EQ(NearestTimestamp(times, 50.0), 5u);
  EXPECT_THROW(NearestTimestamp({}, 1.0), Error);
}

TEST(KittiOxts, BadInputIsOneClearError) {
  TempDir tmp("oxts_bad");
  const fs::path drive = tmp.path / "drive_sync";
  fs::create_directories(drive / "oxts" / "data");
  std::ofstream(drive / "oxts" / "data" / "0000000000.txt") << "49.0 8.4 115\n";  // 3 numbers only
  testing::WriteRawCalibration(tmp.path);
  try {
    OxtsCameraPoses(drive.string(), 0);
    FAIL() << "a short packet must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("0000000000.txt"), std::string::npos) << e.what();
  }
  fs::remove(tmp.path / "calib_velo_to_cam.txt");
  std::ofstream(drive / "oxts" / "data" / "0000000000.txt") << "49.0 8.4 115 0 0 0\n";
  try {
    OxtsCameraPoses(drive.string(), 0);
    FAIL() << "a missing calibration file must throw";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("calib_velo_to_cam.txt"), std::string::npos) << e.what();
  }
  const testing::CliRun run = testing::RunDvso("oxts-poses --sequence " + (tmp.path / "nothing").string() + " --out " +
                                               (tmp.path / "p.txt").string());
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.out.find("dvso: error:"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(tmp.path / "p.txt"));
}

}  // namespace
}  // namespace dvso
