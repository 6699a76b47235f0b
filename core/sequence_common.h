// Internal helpers shared by the sequence readers (not part of the public API).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace dvso::internal {

// Loads an image as CV_8UC1 grey (colour is converted); throws dvso::Error
// naming the file when missing/undecodable or not of the expected size
// (expected size 0x0 = no check). 16-bit images are scaled to 8 bit.
cv::Mat LoadGreyImage(const std::string& path, cv::Size expected = {});
// Loads an image as CV_8UC3 (BGR); same checks.
cv::Mat LoadColorImage(const std::string& path, cv::Size expected = {});
// Sorted list of image files (png, jpg, jpeg, pgm, bmp) in a directory.
std::vector<std::string> ListImages(const std::string& directory);

}  // namespace dvso::internal
