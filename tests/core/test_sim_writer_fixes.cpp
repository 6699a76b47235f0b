// Reruns of `dvso simulate` into an existing folder (core/simulator_writer.cpp) and what the readers make
// of the folders they leave: no metadata of an earlier run beside a half-written new one, no emptied
// colour folders taken for a colour camera, no temporary files of a killed writer taken for frames.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/disparity_io.h"
#include "core/error.h"
#include "core/kitti_raw_writer.h"
#include "core/sequence.h"
#include "core/sequence_common.h"
#include "core/simulator.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {

namespace fs = std::filesystem;

// The smallest simulation that is still a stereo sequence: two frames of 96x32 on a generated path.
SimulatorOptions TinyOptions(bool color) {
  SimulatorOptions o;
  o.num_frames = 2;
  o.camera = StereoCamera{}.Resized(96, 32);
  o.texture_size = 64;
  o.num_threads = 1;
  o.color = color;
  return o;
}

void Touch(const fs::path& path) { std::ofstream(path) << "x"; }

TEST(SimulatorRerun, FailedRerunLeavesNoMetadataOfTheEarlierRun) {
  const testing::TempDir dir("sim_rerun_fails");
  const std::string seq = dir / "seq";
  WriteSimulatedSequence(TinyOptions(false), seq, false);
  ASSERT_TRUE(fs::exists(fs::path(seq) / "poses.txt"));
  // The rerun fails at frame 1: a folder holds the name of its left image.
  const fs::path blocked = fs::path(seq) / "image_0" / "000001.png";
  fs::remove(blocked);
  fs::create_directories(blocked / "blocker");
  EXPECT_THROW(WriteSimulatedSequence(TinyOptions(false), seq, false), Error);
  // Frame 0 is new, frame 1 old: the earlier run's poses and times must not pass for this mix.
  for (const char* file : {"calib.txt", "times.txt", "poses.txt", "exposures.txt", "simulation.yaml"}) {
    EXPECT_FALSE(fs::exists(fs::path(seq) / file)) << file;
  }
  EXPECT_THROW(OpenSequence(seq), Error);  // recognisably incomplete
}

TEST(SimulatorRerun, GreyRerunAfterAColourRunLeavesNoColourFolders) {
  const testing::TempDir dir("sim_rerun_grey");
  const std::string seq = dir / "seq";
  WriteSimulatedSequence(TinyOptions(true), seq, false);
  ASSERT_TRUE(OpenSequence(seq)->has_color());
  WriteSimulatedSequence(TinyOptions(false), seq, false);
  EXPECT_FALSE(fs::exists(fs::path(seq) / "image_2"));
  EXPECT_FALSE(fs::exists(fs::path(seq) / "image_3"));
  const std::unique_ptr<SequenceReader> sequence = OpenSequence(seq);
  EXPECT_FALSE(sequence->has_color());
  EXPECT_EQ(sequence->size(), 2);
}

// The reader itself: an image_2/ without images is no colour camera (left by hand, or by a colour folder
// holding files of someone else's that the simulator would not remove).
TEST(KittiSequenceColour, EmptyColourFolderIsNoColourCamera) {
  const testing::TempDir dir("kitti_empty_colour");
  WriteKittiCalibration(dir / "calib.txt", StereoCamera{}.Resized(96, 32));  // P2/P3 = P0/P1: colour at the grey centres
  const cv::Mat image(32, 96, CV_8UC1, cv::Scalar(100));
  for (const char* sub : {"image_0", "image_1", "image_2"}) fs::create_directories(dir.path / sub);
  ASSERT_TRUE(cv::imwrite(dir / "image_0/000000.png", image));
  ASSERT_TRUE(cv::imwrite(dir / "image_1/000000.png", image));
  EXPECT_FALSE(OpenKittiSequence(dir.path.string())->has_color());
  // ... while the same folder with a colour image is colour (the calibration is not what says no above).
  ASSERT_TRUE(cv::imwrite(dir / "image_2/000000.png", cv::Mat(32, 96, CV_8UC3, cv::Scalar(10, 20, 30))));
  EXPECT_TRUE(OpenKittiSequence(dir.path.string())->has_color());
}

// The pair a reader reports is the one it reads: the colour pair asked for, or colour where a folder has no
// grey cameras (labels and predicted maps record it, training and odometry compare it).
TEST(KittiSequenceColour, ThePairReadIsReported) {
  const testing::TempDir dir("kitti_pair_read");
  WriteKittiCalibration(dir / "calib.txt", StereoCamera{}.Resized(96, 32));
  const cv::Mat grey(32, 96, CV_8UC1, cv::Scalar(100));
  const cv::Mat colour(32, 96, CV_8UC3, cv::Scalar(10, 20, 30));
  for (const char* sub : {"image_2", "image_3"}) {
    fs::create_directories(dir.path / sub);
    ASSERT_TRUE(cv::imwrite(dir / (std::string(sub) + "/000000.png"), colour));
  }
  EXPECT_EQ(OpenKittiSequence(dir.path.string())->camera_pair(), CameraPair::kColour);  // no grey cameras
  for (const char* sub : {"image_0", "image_1"}) {
    fs::create_directories(dir.path / sub);
    ASSERT_TRUE(cv::imwrite(dir / (std::string(sub) + "/000000.png"), grey));
  }
  EXPECT_EQ(OpenKittiSequence(dir.path.string())->camera_pair(), CameraPair::kGrey);
  EXPECT_EQ(OpenKittiSequence(dir.path.string(), CameraPair::kColour)->camera_pair(), CameraPair::kColour);
}

TEST(KittiSequenceColour, RecordedPairIsReadStrictly) {
  const testing::TempDir dir("recorded_pair");
  EXPECT_FALSE(RecordedCameraPair(dir / "none.json").has_value());  // no record
  std::ofstream(dir / "old.json") << "{\"sequence\": \"s\"}";
  EXPECT_FALSE(RecordedCameraPair(dir / "old.json").has_value());  // written before outputs named their pair
  std::ofstream(dir / "colour.json") << "{\"cameras\": \"colour\"}";
  EXPECT_EQ(RecordedCameraPair(dir / "colour.json"), CameraPair::kColour);
  std::ofstream(dir / "odd.json") << "{\"cameras\": \"infrared\"}";
  EXPECT_THROW(RecordedCameraPair(dir / "odd.json"), Error);
  std::ofstream(dir / "broken.json") << "{\"cameras\": ";
  EXPECT_THROW(RecordedCameraPair(dir / "broken.json"), Error);
}

// A writer killed between writing and renaming leaves NAME.tmp-writing.png (core/fs_util.h): never a frame.
TEST(SequenceListing, UnfinishedAtomicWritesAreNoFrames) {
  const testing::TempDir dir("list_unfinished");
  for (const char* name : {"000000.png", "000001.png", "000001.tmp-writing.png", "000002.tmp-writing.png"}) {
    Touch(dir.path / name);
  }
  const std::vector<std::string> files = internal::ListImages(dir.path.string());
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(fs::path(files[0]).filename().string(), "000000.png");
  EXPECT_EQ(fs::path(files[1]).filename().string(), "000001.png");
}

TEST(SimulatorRerun, RerunsRemoveUnfinishedAtomicWrites) {
  const testing::TempDir dir("sim_rerun_unfinished");
  const std::string seq = dir / "seq", raw = dir / "raw";
  WriteSimulatedSequence(TinyOptions(false), seq, false);
  const std::string drive = WriteKittiRawDrive(seq, raw, KittiRawDriveOptions{}).drive_dir;
  // What a kill between write and rename leaves behind, in each kind of folder.
  const std::vector<fs::path> leftovers = {
      fs::path(seq) / "image_0" / "000005.tmp-writing.png", fs::path(seq) / "times.tmp-writing.txt",
      fs::path(drive) / "image_00" / "data" / "0000000005.tmp-writing.png",
      fs::path(drive) / "oxts" / "timestamps.tmp-writing.txt"};
  for (const fs::path& path : leftovers) Touch(path);
  WriteSimulatedSequence(TinyOptions(false), seq, false);
  WriteKittiRawDrive(seq, raw, KittiRawDriveOptions{});
  for (const fs::path& path : leftovers) EXPECT_FALSE(fs::exists(path)) << path.string();
  EXPECT_TRUE(fs::exists(fs::path(drive) / "image_00" / "data" / "0000000001.png"));
}

// What `dvso predict` applies before writing its maps: a disparity the KITTI PNG cannot hold (>= 256 px;
// the network outputs up to 0.3 * width) becomes invalid instead of being clamped to 255.996 px.
TEST(KittiMapRange, DisparityBeyondThePngRangeIsWrittenAsInvalid) {
  const testing::TempDir dir("map_range");
  cv::Mat map(1, 3, CV_32F);
  map.at<float>(0, 0) = 300.f;
  map.at<float>(0, 1) = 100.f;
  map.at<float>(0, 2) = 255.5f;
  const cv::Mat checked = InvalidBeyondKittiMapRange(map);
  EXPECT_EQ(checked.at<float>(0, 0), 0.f);
  EXPECT_EQ(checked.at<float>(0, 1), 100.f);
  EXPECT_EQ(checked.at<float>(0, 2), 255.5f);
  EXPECT_EQ(map.at<float>(0, 0), 300.f);  // a copy: the caller's map (e.g. for the preview) is unchanged
  WriteKittiMapPng(dir / "checked.png", checked);
  const cv::Mat read = ReadKittiMapPng(dir / "checked.png");
  EXPECT_EQ(read.at<float>(0, 0), 0.f);  // invalid, not a wrong far disparity
  EXPECT_FLOAT_EQ(read.at<float>(0, 1), 100.f);
  // Unchecked, the PNG would say 255.996 px: a depth ~15 % too far for a 300 px disparity.
  WriteKittiMapPng(dir / "clamped.png", map);
  EXPECT_FLOAT_EQ(ReadKittiMapPng(dir / "clamped.png").at<float>(0, 0), kKittiMapMaxValue);
}

}  // namespace
}  // namespace dvso
