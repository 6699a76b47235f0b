// KITTI odometry layout reader (also what `dvso simulate` writes).
#include <cmath>
#include <filesystem>
#include <map>
#include <fstream>
#include <iomanip>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "core/sequence_common.h"
#include "core/trajectory.h"

namespace dvso {

namespace fs = std::filesystem;

StereoCamera ReadKittiCalibration(const std::string& calib_path, int width, int height) {
  std::ifstream in(calib_path);
  RequireFile(in.good(), calib_path, "cannot open calibration file");
  std::map<std::string, std::vector<double>> rows;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const auto colon = line.find(':');
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    RequireFile(colon != std::string::npos, calib_path,
                "line " + std::to_string(line_number) + ": expected 'NAME: values'");
    const std::string name = line.substr(0, colon);
    std::istringstream values(line.substr(colon + 1));
    std::vector<double> v;
    std::string token;
    while (values >> token) {
      char* end = nullptr;
      const double x = std::strtod(token.c_str(), &end);
      RequireFile(end != token.c_str() && *end == '\0' && std::isfinite(x), calib_path,
                  "line " + std::to_string(line_number) + ": '" + token + "' is not a finite number");
      v.push_back(x);
    }
    if (name == "P0" || name == "P1" || name == "P2" || name == "P3") {
      RequireFile(v.size() == 12, calib_path,
                  "line " + std::to_string(line_number) + ": " + name + " needs 12 numbers, got " +
                      std::to_string(v.size()));
    }
    rows[name] = v;
  }
  RequireFile(rows.count("P0") == 1, calib_path, "missing P0 line");
  const auto& p0 = rows["P0"];
  StereoCamera camera;
  camera.left.fx = p0[0];
  camera.left.fy = p0[5];
  camera.left.cx = p0[2];
  camera.left.cy = p0[6];
  camera.left.width = width;
  camera.left.height = height;
  camera.baseline = 0.0;
  if (rows.count("P1") == 1) {
    const auto& p1 = rows["P1"];
    RequireFile(p1[0] > 0, calib_path, "P1 has a non-positive focal length");
    // P1 = K [I | -b e_x] (relative to camera 0), so P1[0][3] = -fx * b.
    camera.baseline = -(p1[3] - p0[3]) / p1[0];
    RequireFile(camera.baseline > 0, calib_path, "P1 gives a non-positive stereo baseline");
  }
  try {
    camera.left.Check();
  } catch (const Error& e) {
    throw Error(calib_path, e.what());
  }
  return camera;
}

void WriteKittiCalibration(const std::string& calib_path, const StereoCamera& camera) {
  WriteAtomically(calib_path, [&](const std::string& temp) {
    std::ofstream out(temp);
    RequireFile(out.good(), calib_path, "cannot write calibration file");
    out << std::scientific << std::setprecision(12);
    const auto& c = camera.left;
    for (int i = 0; i < 4; ++i) {
      // Grey pair (0, 1) and colour pair (2, 3) share the rectified geometry here.
      const double tx = (i % 2 == 1) ? -c.fx * camera.baseline : 0.0;
      out << "P" << i << ": " << c.fx << " 0 " << c.cx << " " << tx << " 0 " << c.fy << " " << c.cy
          << " 0 0 0 1 0\n";
    }
  });
}

namespace {

class KittiSequence : public SequenceReader {
 public:
  explicit KittiSequence(const std::string& root) : root_(root) {
    const std::string calib = JoinPath(root, "calib.txt");
    RequireFile(fs::is_regular_file(calib), calib, "missing calibration file (KITTI layout needs calib.txt)");
    // Grey images are preferred; colour-only folders (image_2/image_3) are converted.
    if (fs::is_directory(JoinPath(root, "image_0"))) {
      left_dir_ = JoinPath(root, "image_0");
      right_dir_ = JoinPath(root, "image_1");
    } else {
      left_dir_ = JoinPath(root, "image_2");
      right_dir_ = JoinPath(root, "image_3");
    }
    files_ = internal::ListImages(left_dir_);
    RequireFile(!files_.empty(), left_dir_, "no images found");
    const cv::Mat first = internal::LoadGreyImage(files_[0]);
    camera_ = ReadKittiCalibration(calib, first.cols, first.rows);
    stereo_ = camera_.baseline > 0 && fs::is_directory(right_dir_);
    color_ = fs::is_directory(JoinPath(root, "image_2"));
    const std::string times = JoinPath(root, "times.txt");
    if (fs::is_regular_file(times)) {
      timestamps_ = ReadTimes(times);
      RequireFile(timestamps_.size() == files_.size(), times,
                  "has " + std::to_string(timestamps_.size()) + " timestamps for " +
                      std::to_string(files_.size()) + " images");
    } else {
      for (size_t i = 0; i < files_.size(); ++i) timestamps_.push_back(0.1 * i);
    }
  }

  int size() const override { return static_cast<int>(files_.size()); }
  bool is_stereo() const override { return stereo_; }
  bool has_color() const override { return color_; }
  const StereoCamera& camera() const override { return camera_; }
  const std::vector<double>& timestamps() const override { return timestamps_; }
  const std::string& root() const override { return root_; }
  std::string FrameName(int index) const override { return fs::path(files_.at(index)).stem().string(); }

  StereoFrame Read(int index, const SequenceReadOptions& options) const override {
    Require(index >= 0 && index < size(), root_ + ": frame " + std::to_string(index) + " out of range");
    const cv::Size size(camera_.left.width, camera_.left.height);
    const std::string name = fs::path(files_[index]).filename().string();
    StereoFrame frame;
    frame.index = index;
    frame.timestamp = timestamps_[index];
    frame.left = internal::LoadGreyImage(files_[index], size);
    if (options.load_right && stereo_) frame.right = internal::LoadGreyImage(JoinPath(right_dir_, name), size);
    if (options.load_color && color_) {
      frame.left_color = internal::LoadColorImage(JoinPath(JoinPath(root_, "image_2"), name), size);
      if (options.load_right && fs::is_directory(JoinPath(root_, "image_3"))) {
        frame.right_color = internal::LoadColorImage(JoinPath(JoinPath(root_, "image_3"), name), size);
      }
    }
    return frame;
  }

 private:
  std::string root_, left_dir_, right_dir_;
  std::vector<std::string> files_;
  StereoCamera camera_;
  bool stereo_ = false, color_ = false;
  std::vector<double> timestamps_;
};

}  // namespace

std::unique_ptr<SequenceReader> OpenKittiSequence(const std::string& path) {
  return std::make_unique<KittiSequence>(path);
}

}  // namespace dvso
