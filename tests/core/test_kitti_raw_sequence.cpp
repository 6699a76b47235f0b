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

#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

// `dvso odometry --mode stereo` of `sequence` into `out`: its trajectory, or an empty one (and a test
// failure naming the output) when the run fails.
Trajectory StereoOdometry(const fs::path& sequence, const fs::path& out) {
  const testing::CliRun run =
      testing::RunDvso("odometry --no-progress --mode stereo --sequence " + sequence.string() + " --out " + out.string());
  if (run.exit_code != 0) {
    ADD_FAILURE() << run.out;
    return {};
  }
  return ReadTrajectory((out / "trajectory.txt").string());
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
  const Trajectory a = StereoOdometry(seq, fs::path(dir) / "out_odometry");
  const Trajectory b = StereoOdometry(drive, fs::path(dir) / "out_raw");
  ASSERT_FALSE(a.empty() || b.empty());
  ASSERT_EQ(a.size(), b.size());
  EXPECT_LT((a.poses.back().T_world_camera.translation() - b.poses.back().T_world_camera.translation()).norm(), 1e-3);

  // A frame without its right image is skipped, and the rest stay paired by name.
  fs::remove(drive / "image_01" / "data" / RawName(5, ".png"));
  const std::unique_ptr<SequenceReader> gappy = OpenSequence(drive.string());
  ASSERT_EQ(gappy->size(), odometry_layout->size() - 1);
  EXPECT_EQ(gappy->FrameName(5), "0000000006");
  EXPECT_EQ(cv::norm(gappy->Read(5).right, odometry_layout->Read(6).right, cv::NORM_INF), 0.0);
}

// Rewrites `seq` as an unrectified extract drive: images distorted with D = (k1, k2, 0, 0, 0) (R_rect = I),
// each camera numbering its own frames, and the right camera dropping frame `dropped`.
fs::path WriteAsExtractDrive(const fs::path& seq, const fs::path& date_dir, int dropped) {
  const fs::path drive = date_dir / "2011_09_26_drive_0001_extract";
  const std::unique_ptr<SequenceReader> reader = OpenSequence(seq.string());
  const StereoCamera& cam = reader->camera();
  const cv::Size size(cam.left.width, cam.left.height);
  const cv::Mat K = (cv::Mat_<double>(3, 3) << cam.left.fx, 0, cam.left.cx, 0, cam.left.fy, cam.left.cy, 0, 0, 1);
  const cv::Mat D = (cv::Mat_<double>(1, 5) << -0.08, 0.03, 0, 0, 0);
  // Distorted pixel -> rectified pixel, to sample the rectified image at.
  std::vector<cv::Point2f> grid;
  for (int v = 0; v < size.height; ++v)
    for (int u = 0; u < size.width; ++u) grid.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> rectified;
  cv::undistortPoints(grid, rectified, K, D, cv::noArray(), K);
  cv::Mat map_x(size, CV_32F), map_y(size, CV_32F);
  for (size_t i = 0; i < grid.size(); ++i) {
    map_x.at<float>(static_cast<int>(grid[i].y), static_cast<int>(grid[i].x)) = rectified[i].x;
    map_y.at<float>(static_cast<int>(grid[i].y), static_cast<int>(grid[i].x)) = rectified[i].y;
  }
  std::ofstream calib(date_dir / "calib_cam_to_cam.txt");
  calib.precision(17);
  for (int id : {0, 1}) {
    const double tx = id == 0 ? 0.0 : -cam.left.fx * cam.baseline;
    calib << "S_0" << id << ": " << size.width << " " << size.height << "\nK_0" << id << ": " << cam.left.fx << " 0 "
          << cam.left.cx << " 0 " << cam.left.fy << " " << cam.left.cy << " 0 0 1\nD_0" << id
          << ": -0.08 0.03 0 0 0\nR_rect_0" << id << ": 1 0 0 0 1 0 0 0 1\nS_rect_0" << id << ": " << size.width << " "
          << size.height << "\nP_rect_0" << id << ": " << cam.left.fx << " 0 " << cam.left.cx << " " << tx << " 0 "
          << cam.left.fy << " " << cam.left.cy << " 0 0 0 1 0\n";
  }
  for (const char* id : {"00", "01"}) {
    const fs::path camera_dir = drive / ("image_" + std::string(id));
    fs::create_directories(camera_dir / "data");
    std::ofstream times(camera_dir / "timestamps.txt");
    int written = 0;
    for (int i = 0; i < reader->size(); ++i) {
      if (id == std::string("01") && i == dropped) continue;
      const double t = reader->timestamps()[i] + (id == std::string("01") ? 0.0004 : 0.0);  // trigger jitter
      char stamp[64];
      std::snprintf(stamp, sizeof(stamp), "2011-09-26 13:02:%02d.%09d", 10 + static_cast<int>(t),
                    static_cast<int>(std::lround((t - std::floor(t)) * 1e9)));
      times << stamp << "\n";
      const StereoFrame frame = reader->Read(i);
      cv::Mat distorted;
      cv::remap(id == std::string("00") ? frame.left : frame.right, distorted, map_x, map_y, cv::INTER_LINEAR,
                cv::BORDER_REPLICATE);
      cv::imwrite((camera_dir / "data" / RawName(written++, ".png")).string(), distorted);
    }
  }
  return drive;
}

TEST(KittiRawSequence, ExtractDriveIsRectifiedOnReadAndPairedByTimestamp) {
  const std::string dir = testing::FreshSimulatedSequence("kitti_raw_extract", 40);
  ASSERT_FALSE(dir.empty());
  const fs::path seq = fs::path(dir) / "seq";
  const fs::path drive = WriteAsExtractDrive(seq, fs::path(dir), /*dropped=*/5);
  const std::unique_ptr<SequenceReader> odometry_layout = OpenSequence(seq.string());
  const std::unique_ptr<SequenceReader> raw = OpenSequence(drive.string());
  ASSERT_EQ(raw->size(), odometry_layout->size() - 1);  // the frame the right camera dropped
  EXPECT_EQ(raw->FrameName(5), "0000000006");
  // Rectified on read: the interior matches the original rectified images (two interpolations apart);
  // left frame 6 pairs with the right camera's 6th file, which holds frame 6.
  for (int i : {0, 5, 38}) {
    const int original = i < 5 ? i : i + 1;
    const StereoFrame a = raw->Read(i), b = odometry_layout->Read(original);
    const cv::Rect interior(20, 10, a.left.cols - 40, a.left.rows - 20);
    cv::Mat left_diff, right_diff;
    cv::absdiff(a.left(interior), b.left(interior), left_diff);
    cv::absdiff(a.right(interior), b.right(interior), right_diff);
    EXPECT_LT(cv::mean(left_diff)[0], 4.0) << "frame " << i;
    EXPECT_LT(cv::mean(right_diff)[0], 4.0) << "frame " << i;
  }
  // Without rectification the distortion would show: compare the raw file itself.
  const cv::Mat raw_file = cv::imread((drive / "image_00" / "data" / RawName(20, ".png")).string(), cv::IMREAD_GRAYSCALE);
  ASSERT_EQ(raw->FrameName(19), "0000000020");
  cv::Mat raw_diff, rectified_diff;
  cv::absdiff(raw_file, odometry_layout->Read(20).left, raw_diff);
  cv::absdiff(raw->Read(19).left, odometry_layout->Read(20).left, rectified_diff);
  const cv::Rect interior(20, 10, raw_file.cols - 40, raw_file.rows - 20);
  EXPECT_LT(cv::mean(rectified_diff(interior))[0], 0.5 * cv::mean(raw_diff(interior))[0]);

  // Stereo odometry on the extract drive stays close to the one on the rectified sequence.
  const Trajectory a = StereoOdometry(seq, fs::path(dir) / "out_odometry");
  const Trajectory b = StereoOdometry(drive, fs::path(dir) / "out_raw");
  ASSERT_FALSE(a.empty() || b.empty());
  ASSERT_EQ(b.size() + 1, a.size());
  const double drift = (a.poses.back().T_world_camera.translation() - b.poses.back().T_world_camera.translation()).norm();
  EXPECT_LT(drift, 0.02 * a.PathLength()) << "drift " << drift << " m over " << a.PathLength() << " m";
}

}  // namespace
}  // namespace dvso
