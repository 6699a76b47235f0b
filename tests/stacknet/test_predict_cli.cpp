// `dvso predict --images DIR` keeps the input file names (as .png), through
// the real binary with an untrained tiny model.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "core/disparity_io.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {
namespace fs = std::filesystem;

class PredictCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = dvso::testing::ScratchDir("predict_cli");
    fs::create_directories(dir_ / "images");
    model_ = (dir_ / "tiny.pt").string();
    const std::string export_cmd = std::string(DVSO_BINARY) + " export --config " + DVSO_TEST_DATA_DIR +
                                   "/../configs/stacknet_tiny.yaml --random-init --model simple --training-baseline 0.54 "
                                   "--training-fx-over-width 0.58 --out " + model_ +
                                   " > /dev/null 2>&1";
    ASSERT_EQ(std::system(export_cmd.c_str()), 0);
  }
  void TearDown() override { fs::remove_all(dir_); }
  int Predict(const std::string& extra = "") {
    const std::string cmd = std::string(DVSO_BINARY) + " predict --model " + model_ + " --images " +
                            (dir_ / "images").string() + " --out " + (dir_ / "out").string() + " " + extra +
                            " > /dev/null 2>&1";
    return std::system(cmd.c_str());
  }
  void WriteImage(const std::string& name, int width, int height) {
    cv::Mat image(height, width, CV_8UC3);
    cv::randu(image, 0, 255);
    ASSERT_TRUE(cv::imwrite((dir_ / "images" / name).string(), image));
  }
  fs::path dir_;
  std::string model_;
};

TEST_F(PredictCli, ImagesKeepTheirNames) {
  WriteImage("zeta_frame.png", 96, 40);
  WriteImage("0042.jpg", 80, 32);
  ASSERT_EQ(Predict(), 0);
  for (const char* sub : {"left", "right", "left_color", "right_color"}) {
    EXPECT_TRUE(fs::exists(dir_ / "out" / sub / "zeta_frame.png")) << sub;
    EXPECT_TRUE(fs::exists(dir_ / "out" / sub / "0042.png")) << sub;
    EXPECT_FALSE(fs::exists(dir_ / "out" / sub / "000000.png")) << sub << ": renumbered";
  }
  // Maps at the input image's resolution.
  const cv::Mat left = ReadKittiMapPng((dir_ / "out" / "left" / "0042.png").string());
  EXPECT_EQ(left.cols, 80);
  EXPECT_EQ(left.rows, 32);
}

// A preview is written like the maps: through a temporary file moved into place, and a failed write
// is an error (it was ignored: the command said it wrote the previews).
TEST_F(PredictCli, APreviewThatCannotBeWrittenIsAnError) {
  WriteImage("a.png", 64, 32);
  // The preview's temporary file cannot be created: a folder has its name.
  fs::create_directories(dir_ / "out" / "left_color" / "a.tmp-writing.png" / "blocker");
  const dvso::testing::CliRun run = dvso::testing::RunDvso(
      "predict --model " + model_ + " --images " + (dir_ / "images").string() + " --out " + (dir_ / "out").string());
  EXPECT_NE(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("left_color/a.png"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("cannot create the file"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(dir_ / "out" / "left_color" / "a.png"));
}

// `dvso bench` measures at the model's own input size unless told otherwise (the tiny config: 64x32).
TEST_F(PredictCli, BenchDefaultsToTheModelsInputSize) {
  const std::string bench = "bench --device cpu --threads 1 --warmup 1 --runs 3 --json --model " + model_;
  const dvso::testing::CliRun defaults = dvso::testing::RunDvso(bench, /*merge_stderr=*/false);
  ASSERT_EQ(defaults.exit_code, 0);
  EXPECT_NE(defaults.out.find("\"width\": 64"), std::string::npos) << defaults.out;
  EXPECT_NE(defaults.out.find("\"height\": 32"), std::string::npos) << defaults.out;
  const dvso::testing::CliRun given = dvso::testing::RunDvso(bench + " --width 128 --height 64", /*merge_stderr=*/false);
  ASSERT_EQ(given.exit_code, 0);
  EXPECT_NE(given.out.find("\"width\": 128"), std::string::npos) << given.out;
}

// The images of a folder are those the sequence readers list (any case; .pgm/.bmp too), so that
// `odometry --sequence` over them finds a map for every frame.
TEST_F(PredictCli, ImagesAreListedLikeTheSequenceReadersListThem) {
  WriteImage("a.png", 64, 32);
  WriteImage("b.png", 64, 32);
  fs::rename(dir_ / "images" / "b.png", dir_ / "images" / "b.PNG");  // the encoder is chosen by extension
  WriteImage("c.bmp", 64, 32);
  ASSERT_EQ(Predict("--no-color"), 0);
  for (const char* sub : {"left", "right"}) {
    for (const char* name : {"a.png", "b.png", "c.png"})
      EXPECT_TRUE(fs::exists(dir_ / "out" / sub / name)) << sub << "/" << name;
    const fs::directory_iterator maps(dir_ / "out" / sub);
    EXPECT_EQ(std::distance(fs::begin(maps), fs::end(maps)), 3) << sub << ": other maps than the inputs'";
  }
}

TEST_F(PredictCli, TwoImagesWithTheSameNameAreAnError) {
  WriteImage("a.png", 64, 32);
  WriteImage("a.jpg", 64, 32);
  EXPECT_NE(Predict("--no-color"), 0);
  EXPECT_FALSE(fs::exists(dir_ / "out")) << "output folders made for inputs that were refused";
}

TEST_F(PredictCli, EmptyImageFolderLeavesNoOutputAndNoColorMakesNoPreviewFolders) {
  EXPECT_NE(Predict(), 0);  // no images
  EXPECT_FALSE(fs::exists(dir_ / "out"));
  WriteImage("a.png", 64, 32);
  ASSERT_EQ(Predict("--no-color"), 0);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "left" / "a.png"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "right" / "a.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "left_color"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "right_color"));
  // With previews, then again without: the stale previews of a.png go, another image's preview stays.
  WriteImage("b.png", 64, 32);
  ASSERT_EQ(Predict(), 0);
  ASSERT_TRUE(fs::exists(dir_ / "out" / "left_color" / "a.png"));
  fs::remove(dir_ / "images" / "b.png");
  ASSERT_EQ(Predict("--no-color"), 0);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "left_color" / "a.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "right_color" / "a.png"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "left_color" / "b.png")) << "not this run's image: left alone";
  // Once a run has removed every preview, the emptied preview folders go too.
  WriteImage("b.png", 64, 32);
  ASSERT_EQ(Predict("--no-color"), 0);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "left_color"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "right_color"));
}

// On a KITTI raw drive the network sees the colour pair and the maps are named like the drive's frames
// (file numbers), so they feed `odometry --mode dvso --cameras colour` unchanged; an extract drive's
// frame without a right image has no map.
TEST_F(PredictCli, RawDriveMapsAreNamedLikeItsFramesAndFeedTheOdometry) {
  const std::string seq = (dir_ / "seq").string();
  const std::string sim = std::string(DVSO_BINARY) + " simulate --quiet --out " + seq +
                          " --count 12 --width 320 --height 96 --texture-size 128 --color --raw-layout extract "
                          "--raw-drop-every 5 > /dev/null 2>&1";
  ASSERT_EQ(std::system(sim.c_str()), 0) << sim;
  const std::string drive = seq + "/kitti_raw/2011_09_26/2011_09_26_drive_0001_extract";
  const std::string out = (dir_ / "raw_out").string();
  const std::string predict = std::string(DVSO_BINARY) + " predict --model " + model_ + " --sequence " + drive +
                              " --out " + out + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(predict.c_str()), 0) << predict;
  EXPECT_TRUE(fs::exists(out + "/left/0000000004.png"));
  EXPECT_FALSE(fs::exists(out + "/left/0000000005.png")) << "frame 5 has no right image";
  EXPECT_TRUE(fs::exists(out + "/right/0000000011.png"));
  EXPECT_FALSE(fs::exists(out + "/left/000000.png")) << "renumbered";
  const std::string odometry = std::string(DVSO_BINARY) + " odometry --mode dvso --cameras colour --no-progress --sequence " +
                               drive + " --disparity-left " + out + "/left --disparity-right " + out + "/right --out " +
                               (dir_ / "odometry").string() + " > /dev/null 2>&1";
  ASSERT_EQ(std::system(odometry.c_str()), 0) << odometry;
  int lines = 0;
  std::string line;
  for (std::ifstream in(dir_ / "odometry" / "trajectory.txt"); std::getline(in, line);) ++lines;
  EXPECT_EQ(lines, 10);  // 12 frames, 5 and 10 without a right image
}

}  // namespace
}  // namespace dvso
