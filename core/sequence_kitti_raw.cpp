// KITTI raw drive reader, rectified ("_sync") drives: DRIVE/image_0X/data/*.png,
// image_0X/timestamps.txt, calibration in the date folder (calib_cam_to_cam.txt:
// P_rect_0X, S_rect_0X; see core/kitti_raw_calibration.h). The grey pair 00/01 is
// used when present, else the colour pair 02/03; colour images (image_02/03) are
// loaded on request as in the KITTI odometry layout. Left and right images are
// paired by file name; a frame without its right image is skipped and counted
// (one warning), never paired with a neighbour.
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_raw_calibration.h"
#include "core/sequence.h"
#include "core/sequence_common.h"

namespace dvso {

namespace fs = std::filesystem;

double ParseKittiRawTimestamp(const std::string& text, const std::string& path) {
  // "2011-09-26 13:02:25.964389445": seconds since the epoch (UTC), nanosecond fraction.
  std::tm tm{};
  std::istringstream in(text);
  in >> std::get_time(&tm, "%Y-%m-%d %H:%M:%S");
  RequireFile(!in.fail(), path, "'" + text + "' is not a 'YYYY-MM-DD HH:MM:SS.fraction' timestamp");
  double fraction = 0.0;
  if (in.peek() == '.') in >> fraction;
  return static_cast<double>(timegm(&tm)) + fraction;
}

namespace {

std::vector<double> ReadRawTimestamps(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open timestamps file");
  std::vector<double> times;
  std::string line;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    times.push_back(ParseKittiRawTimestamp(line, path));
  }
  return times;
}

class KittiRawSequence : public SequenceReader {
 public:
  explicit KittiRawSequence(const std::string& root) : root_(root) {
    const bool grey = fs::is_directory(Camera(0));
    const int left_id = grey ? 0 : 2, right_id = left_id + 1;
    left_dir_ = Camera(left_id);
    right_dir_ = Camera(right_id);
    const std::vector<std::string> left_files = internal::ListImages(left_dir_);
    RequireFile(!left_files.empty(), left_dir_, "no images found");
    const std::string calib_dir = FindRawCalibrationDir(root);
    const std::string cam_to_cam = JoinPath(calib_dir, "calib_cam_to_cam.txt");
    const KittiCalibration c = ReadKittiCalibration(cam_to_cam);
    const std::vector<double>& p_left = CalibrationEntry(c, "P_rect_0" + std::to_string(left_id), 12, cam_to_cam);
    const cv::Mat first = internal::LoadGreyImage(left_files[0]);
    camera_.left.fx = p_left[0];
    camera_.left.fy = p_left[5];
    camera_.left.cx = p_left[2];
    camera_.left.cy = p_left[6];
    camera_.left.width = first.cols;
    camera_.left.height = first.rows;
    try {
      camera_.left.Check();
    } catch (const Error& e) {
      throw Error(cam_to_cam, e.what());
    }
    stereo_ = fs::is_directory(right_dir_);
    if (stereo_) {
      const std::vector<double>& p_right = CalibrationEntry(c, "P_rect_0" + std::to_string(right_id), 12, cam_to_cam);
      // P_rect_0X = K [I | t_X] in rectified camera 00: baseline = (t_left - t_right).x.
      camera_.baseline = (p_left[3] - p_right[3]) / p_left[0];
      RequireFile(camera_.baseline > 0, cam_to_cam, "P_rect gives a non-positive stereo baseline");
    }
    color_ = fs::is_directory(Camera(2));
    const std::vector<double> times = ReadRawTimestamps(JoinPath(fs::path(left_dir_).parent_path().string(),
                                                                 "timestamps.txt"));
    RequireFile(times.size() == left_files.size(), left_dir_,
                std::to_string(times.size()) + " timestamps for " + std::to_string(left_files.size()) + " images");
    int unpaired = 0;
    for (size_t i = 0; i < left_files.size(); ++i) {
      const std::string name = fs::path(left_files[i]).filename().string();
      if (stereo_ && !fs::exists(JoinPath(right_dir_, name))) {
        ++unpaired;
        continue;
      }
      files_.push_back(left_files[i]);
      timestamps_.push_back(times[i] - times[0]);
    }
    RequireFile(!files_.empty(), right_dir_, "no left image has a right image of the same name");
    if (unpaired > 0) {
      std::cerr << "dvso: warning: " << root << ": " << unpaired << " frame(s) without a right image skipped\n";
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
      frame.left_color = internal::LoadColorImage(JoinPath(Camera(2), name), size);
      if (options.load_right && fs::exists(JoinPath(Camera(3), name))) {
        frame.right_color = internal::LoadColorImage(JoinPath(Camera(3), name), size);
      }
    }
    return frame;
  }

 private:
  std::string Camera(int id) const { return JoinPath(JoinPath(root_, "image_0" + std::to_string(id)), "data"); }

  std::string root_, left_dir_, right_dir_;
  std::vector<std::string> files_;
  std::vector<double> timestamps_;
  StereoCamera camera_;
  bool stereo_ = false, color_ = false;
};

}  // namespace

bool IsKittiRawDrive(const std::string& path) {
  return fs::is_directory(JoinPath(path, "image_00/data")) || fs::is_directory(JoinPath(path, "image_02/data"));
}

std::unique_ptr<SequenceReader> OpenKittiRawSequence(const std::string& path) {
  return std::make_unique<KittiRawSequence>(path);
}

}  // namespace dvso
