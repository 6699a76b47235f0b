#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "vo/frame/image_pyramid.h"
#include "vo/frame/photometric_calibration.h"
#include "tests/temp_dir.h"

namespace dvso::vo {
namespace {

TEST(FrontendPhotometric, GammaAndVignetteCorrection) {
  const std::string dir = dvso::testing::ScratchPath("pcalib");
  std::filesystem::create_directories(dir);
  // Inverse response G^-1(i) = i^2 (rescaled to [0, 255] on load).
  {
    std::ofstream g(dir + "/pcalib.txt");
    for (int i = 0; i < 256; ++i) g << i * i << " ";
  }
  cv::Mat vignette(4, 6, CV_8UC1, cv::Scalar(200));
  vignette.at<uint8_t>(0, 0) = 100;  // corner at half brightness
  cv::imwrite(dir + "/vignette.png", vignette);
  const PhotometricCalibration calib = PhotometricCalibration::Load(dir + "/pcalib.txt", dir + "/vignette.png");
  EXPECT_NEAR(calib.inverse_response()[255], 255.0, 1e-3);
  EXPECT_NEAR(calib.inverse_response()[128], 255.0 * 128 * 128 / (255.0 * 255.0), 1e-3);
  cv::Mat raw(4, 6, CV_8UC1, cv::Scalar(128));
  const cv::Mat corrected = calib.Correct(raw);
  const float centre = corrected.at<float>(2, 3);
  EXPECT_NEAR(centre, 255.0 * 128 * 128 / (255.0 * 255.0), 1e-2);
  EXPECT_NEAR(corrected.at<float>(0, 0), 2.0f * centre, 1e-2);  // vignette 0.5 undone
  // Exposure: the pyramid divides by the exposure time.
  PinholeCamera cam;
  cam.width = 6;
  cam.height = 4;
  cam.cx = 2.5;
  cam.cy = 1.5;
  ImagePyramidOptions po;
  po.max_levels = 1;
  po.min_level_side = 4;
  const ImagePyramid pyr(raw, cam, po, &calib, 2.0);
  EXPECT_NEAR(pyr.level(0).Intensity(3, 2), centre / 2, 1e-2);
}

TEST(FrontendPhotometric, RejectsBadFiles) {
  const std::string dir = dvso::testing::ScratchPath("pcalib_bad");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/short.txt") << "1 2 3";
  EXPECT_THROW(PhotometricCalibration::Load(dir + "/short.txt", ""), Error);
  {
    std::ofstream g(dir + "/decreasing.txt");
    for (int i = 0; i < 256; ++i) g << 255 - i << " ";
  }
  EXPECT_THROW(PhotometricCalibration::Load(dir + "/decreasing.txt", ""), Error);
  EXPECT_THROW(PhotometricCalibration::Load("", dir + "/missing.png"), Error);
}

}  // namespace
}  // namespace dvso::vo
