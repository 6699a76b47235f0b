// Writing image files (PNG plots, maps, rendered frames) so that a full disk is an error, never a
// truncated file in place.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace dvso {

// Encodes `image` in the format of `path`'s extension (cv::imencode) and writes it with
// WriteStreamAtomically. cv::imwrite ignores the result of closing its file, so on a full disk it
// reported success for a PNG cut short; here every byte is written and the close is checked.
// Throws dvso::Error naming `path` when the image cannot be encoded or written.
void WriteImageAtomically(const std::string& path, const cv::Mat& image, const std::vector<int>& params = {});

}  // namespace dvso
