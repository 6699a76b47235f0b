#include "core/image_file.h"

#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/fs_util.h"

namespace dvso {

void WriteImageAtomically(const std::string& path, const cv::Mat& image, const std::vector<int>& params) {
  std::vector<uchar> bytes;
  bool encoded = false;
  try {
    encoded = !image.empty() && cv::imencode(std::filesystem::path(path).extension().string(), image, bytes, params);
  } catch (const cv::Exception& e) {
    throw Error(path, std::string("cannot encode the image: ") + e.what());
  }
  RequireFile(encoded, path, "cannot encode the image (empty, or no encoder for this extension)");
  WriteStreamAtomically(
      path,
      [&](std::ostream& out) {
        out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
      },
      /*binary=*/true);
}

}  // namespace dvso
