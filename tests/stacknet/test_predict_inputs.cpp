// `dvso predict --images DIR`: inputs as the sequence readers see them, and options that would be ignored.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "core/disparity_io.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {
namespace fs = std::filesystem;

// A folder of images has no camera pairs: --cameras is refused before the model is even loaded.
TEST(PredictInputs, CamerasWithImagesIsAnError) {
  const testing::TempDir dir("predict_cameras");
  fs::create_directories(dir.path / "images");
  ASSERT_TRUE(cv::imwrite(dir / "images/a.png", cv::Mat(32, 64, CV_8UC3, cv::Scalar(1, 2, 3))));
  std::ofstream(dir / "model.pt") << "not read";
  const testing::CliRun run = testing::RunDvso("predict --model " + (dir / "model.pt") + " --images " +
                                               (dir / "images") + " --cameras grey --out " + (dir / "out"));
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_NE(run.out.find("--cameras needs --sequence"), std::string::npos) << run.out;
  EXPECT_FALSE(fs::exists(dir.path / "out"));
}

// `jpeg` with an APP1 Exif segment after SOI that says "rotate 90 degrees clockwise to display" (orientation 6).
std::vector<uint8_t> WithExifOrientation6(const std::vector<uint8_t>& jpeg) {
  const std::vector<uint8_t> app1 = {
      0xFF, 0xE1, 0x00, 0x22,                          // APP1, 34 bytes from here on (the length field too)
      'E',  'x',  'i',  'f',  0x00, 0x00,              // Exif header
      'I',  'I',  0x2A, 0x00, 0x08, 0x00, 0x00, 0x00,  // TIFF, little endian, first IFD at 8
      0x01, 0x00,                                      // one entry
      0x12, 0x01, 0x03, 0x00, 0x01, 0x00, 0x00, 0x00,  // tag 0x0112 Orientation, SHORT, count 1
      0x06, 0x00, 0x00, 0x00,                          // value 6
      0x00, 0x00, 0x00, 0x00};                         // no next IFD
  std::vector<uint8_t> out(jpeg.begin(), jpeg.begin() + 2);  // SOI
  out.insert(out.end(), app1.begin(), app1.end());
  out.insert(out.end(), jpeg.begin() + 2, jpeg.end());
  return out;
}

// The sequence readers (and so `odometry --sequence` on the same files) ignore a JPEG's EXIF orientation;
// predict must too, or its map is of the rotated image and does not lie on the frame the odometry tracks.
TEST(PredictInputs, JpegExifOrientationIsIgnoredLikeTheSequenceReadersDo) {
  const testing::TempDir dir("predict_exif");
  fs::create_directories(dir.path / "images");
  const std::string model = dir / "tiny.pt";
  const testing::CliRun exported = testing::RunDvso("export --config " + std::string(DVSO_TEST_DATA_DIR) +
                                                    "/../configs/stacknet_tiny.yaml --random-init --model simple --out " +
                                                    model);
  ASSERT_EQ(exported.exit_code, 0) << exported.out;
  cv::Mat image(32, 80, CV_8UC3);
  cv::randu(image, 0, 255);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg));
  const std::string path = dir / "images/photo.jpg";
  {
    const std::vector<uint8_t> bytes = WithExifOrientation6(jpeg);
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()),
                                                static_cast<std::streamsize>(bytes.size()));
  }
  // The fixture: OpenCV's default reading turns it, the readers' does not.
  ASSERT_EQ(cv::imread(path, cv::IMREAD_COLOR).size(), cv::Size(32, 80)) << "the Exif orientation is not applied";
  ASSERT_EQ(cv::imread(path, cv::IMREAD_UNCHANGED).size(), cv::Size(80, 32));

  const testing::CliRun run = testing::RunDvso("predict --model " + model + " --images " + (dir / "images") +
                                               " --no-color --threads 1 --device cpu --out " + (dir / "out"));
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const cv::Mat map = ReadKittiMapPng(dir / "out/left/photo.png");
  EXPECT_EQ(map.cols, 80);
  EXPECT_EQ(map.rows, 32);
}

// predict records the pair its maps belong to; odometry reading them for another pair is an error naming
// the record (a raw drive's colour maps on its grey images would sit ~6 cm off on KITTI).
TEST(PredictInputs, OdometryRefusesMapsOfAnotherCameraPair) {
  const testing::TempDir dir("predict_pair");
  const testing::CliRun sim = testing::RunDvso("simulate --quiet --out " + (dir / "seq") +
                                               " --count 6 --width 128 --height 64 --color --raw-layout sync");
  ASSERT_EQ(sim.exit_code, 0) << sim.out;
  std::string drive;
  for (const auto& e : fs::recursive_directory_iterator(dir.path / "seq/kitti_raw")) {
    if (e.is_directory() && e.path().filename().string().find("_sync") != std::string::npos) drive = e.path().string();
  }
  ASSERT_FALSE(drive.empty());
  const std::string model = dir / "tiny.pt";
  ASSERT_EQ(testing::RunDvso("export --config " + std::string(DVSO_TEST_DATA_DIR) +
                             "/../configs/stacknet_tiny.yaml --random-init --model simple --training-baseline 0.54 "
                             "--training-fx-over-width 0.58 --out " + model)
                .exit_code,
            0);
  const testing::CliRun predicted =
      testing::RunDvso("predict --model " + model + " --sequence " + drive + " --no-color --out " + (dir / "maps"));
  ASSERT_EQ(predicted.exit_code, 0) << predicted.out;
  std::ifstream info(dir / "maps/prediction_info.json");
  const std::string text((std::istreambuf_iterator<char>(info)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("\"cameras\": \"colour\""), std::string::npos) << text;  // the network's pair on a raw drive
  const std::string files = " --disparity-left " + (dir / "maps/left") + " --disparity-right " + (dir / "maps/right");
  const testing::CliRun grey = testing::RunDvso("odometry --mode dvso --no-progress --sequence " + drive + files +
                                                " --out " + (dir / "grey"));
  EXPECT_EQ(grey.exit_code, 1) << grey.out;
  EXPECT_NE(grey.out.find("prediction_info.json"), std::string::npos) << grey.out;
  EXPECT_NE(grey.out.find("--cameras colour"), std::string::npos) << grey.out;
  EXPECT_FALSE(fs::exists(dir.path / "grey"));
  const testing::CliRun colour = testing::RunDvso("odometry --mode dvso --no-progress --cameras colour --sequence " +
                                                  drive + files + " --out " + (dir / "colour"));
  EXPECT_EQ(colour.exit_code, 0) << colour.out;
}

// Maps `dvso predict` wrote are the network's: `odometry --disparity-left` takes b_v from the model its record
// names, as `--model` would, not the sequence's own baseline (else the scale moves by b_cam / b_t); maps
// without a record keep the camera's baseline, and --virtual-baseline still overrides.
TEST(PredictInputs, OdometryOnPredictedMapsTakesThePredictingModelsVirtualBaseline) {
  const testing::TempDir dir("predict_baseline");
  const testing::CliRun sim =
      testing::RunDvso("simulate --quiet --out " + (dir / "seq") + " --count 6 --width 128 --height 64");
  ASSERT_EQ(sim.exit_code, 0) << sim.out;
  const std::string model = dir / "tiny.pt";
  ASSERT_EQ(testing::RunDvso("export --config " + std::string(DVSO_TEST_DATA_DIR) +
                             "/../configs/stacknet_tiny.yaml --random-init --model simple --training-baseline 0.3125 "
                             "--training-fx-over-width 0.58 --out " + model)
                .exit_code,
            0);
  const testing::CliRun predicted = testing::RunDvso("predict --model " + model + " --sequence " + (dir / "seq") +
                                                     " --no-color --out " + (dir / "maps"));
  ASSERT_EQ(predicted.exit_code, 0) << predicted.out;
  const std::string files = " --disparity-left " + (dir / "maps/left") + " --disparity-right " + (dir / "maps/right");
  auto header_of = [&](const std::string& extra, const std::string& out) {
    const testing::CliRun run = testing::RunDvso("odometry --mode dvso --no-progress --sequence " + (dir / "seq") +
                                                 files + extra + " --out " + (dir / out));
    EXPECT_EQ(run.exit_code, 0) << run.out;
    return run.out;
  };
  const std::string from_model = header_of("", "a");
  EXPECT_NE(from_model.find("virtual baseline 0.3125 m"), std::string::npos) << from_model;
  EXPECT_NE(from_model.find("trained with baseline 0.3125 m"), std::string::npos) << from_model;
  const std::string overridden = header_of(" --virtual-baseline 0.4375", "b");
  EXPECT_NE(overridden.find("virtual baseline 0.4375 m"), std::string::npos) << overridden;
  // Without predict's record: the simulated camera's own baseline (0.537 m, as KITTI's).
  fs::remove(dir.path / "maps/prediction_info.json");
  const std::string from_camera = header_of("", "c");
  EXPECT_EQ(from_camera.find("virtual baseline 0.3125 m"), std::string::npos) << from_camera;
  EXPECT_NE(from_camera.find("virtual baseline 0.537"), std::string::npos) << from_camera;
  // Maps of a model without a training camera: refused as `--model` refuses it, naming the record.
  const std::string no_camera = dir / "no_camera.pt";
  ASSERT_EQ(testing::RunDvso("export --config " + std::string(DVSO_TEST_DATA_DIR) +
                             "/../configs/stacknet_tiny.yaml --random-init --model simple --out " + no_camera)
                .exit_code,
            0);
  ASSERT_EQ(testing::RunDvso("predict --model " + no_camera + " --sequence " + (dir / "seq") + " --no-color --out " +
                             (dir / "maps"))
                .exit_code,
            0);
  const testing::CliRun refused = testing::RunDvso("odometry --mode dvso --no-progress --sequence " + (dir / "seq") +
                                                   files + " --out " + (dir / "d"));
  EXPECT_EQ(refused.exit_code, 1) << refused.out;
  EXPECT_NE(refused.out.find("prediction_info.json: the model that predicted the maps carries no training camera"),
            std::string::npos)
      << refused.out;
}

}  // namespace
}  // namespace dvso
