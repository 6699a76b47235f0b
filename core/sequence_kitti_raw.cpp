// KITTI raw drive reader: DRIVE/image_0X/data/*.png, image_0X/timestamps.txt,
// calibration in the drive or its date folder (calib_cam_to_cam.txt; see
// core/kitti_raw_calibration.h). The grey pair 00/01 is used when present, else
// the colour pair 02/03; colour images (image_02/03) are loaded on request as in
// the KITTI odometry layout.
//  - rectified ("_sync") drives: left and right images are paired by file name;
//  - unrectified ("_extract") drives: every camera is rectified on read with
//    K_0X, D_0X, R_rect_0X, P_rect_0X into S_rect_0X, and the cameras, which drop
//    frames independently, are paired by timestamp (nearest, within
//    kMaxPairingGap).
// A left frame without a partner is skipped and counted (one warning), never
// paired with a neighbour.
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
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

// Extract drives: a left and a right frame belong together when their timestamps differ by less than this
// (the cameras are triggered together at 10 Hz; 10 ms is a tenth of the frame period).
constexpr double kMaxPairingGap = 0.01;

// Undistortion + rectification of one camera of an extract drive into its rectified image.
struct RawRectifier {
  cv::Mat map_x, map_y;
  cv::Size raw_size;
  cv::Mat Apply(const cv::Mat& raw) const {
    cv::Mat rectified;
    cv::remap(raw, rectified, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
    return rectified;
  }
};

RawRectifier MakeRectifier(const KittiCalibration& c, int id, const std::string& path) {
  const std::string x = "_0" + std::to_string(id);
  const std::vector<double>& k = CalibrationEntry(c, "K" + x, 9, path);
  const std::vector<double>& d = CalibrationEntry(c, "D" + x, 5, path);
  const std::vector<double>& r = CalibrationEntry(c, "R_rect" + x, 9, path);
  const std::vector<double>& p = CalibrationEntry(c, "P_rect" + x, 12, path);
  const std::vector<double>& raw = CalibrationEntry(c, "S" + x, 2, path);
  const std::vector<double>& rect = CalibrationEntry(c, "S_rect" + x, 2, path);
  cv::Mat K(3, 3, CV_64F), R(3, 3, CV_64F), P(3, 3, CV_64F), D(1, 5, CV_64F);
  for (int i = 0; i < 9; ++i) K.at<double>(i / 3, i % 3) = k[i], R.at<double>(i / 3, i % 3) = r[i];
  for (int i = 0; i < 9; ++i) P.at<double>(i / 3, i % 3) = p[(i / 3) * 4 + i % 3];
  for (int i = 0; i < 5; ++i) D.at<double>(0, i) = d[i];
  RawRectifier rectifier;
  rectifier.raw_size = cv::Size(static_cast<int>(std::lround(raw[0])), static_cast<int>(std::lround(raw[1])));
  const cv::Size rect_size(static_cast<int>(std::lround(rect[0])), static_cast<int>(std::lround(rect[1])));
  cv::initUndistortRectifyMap(K, D, R, P, rect_size, CV_32FC1, rectifier.map_x, rectifier.map_y);
  return rectifier;
}

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
    extract_ = fs::path(root).lexically_normal().filename().string().find("_extract") != std::string::npos;
    const bool grey = fs::is_directory(Camera(0));
    const int left_id = grey ? 0 : 2, right_id = left_id + 1;
    const std::string left_dir = Camera(left_id), right_dir = Camera(right_id);
    const std::vector<std::string> left_files = internal::ListImages(left_dir);
    RequireFile(!left_files.empty(), left_dir, "no images found");
    const RawCameraCalibration calibration(FindRawCalibrationDir(root));
    const KittiCalibration& c = calibration.entries;
    const std::string& cam_to_cam = calibration.path;
    const Eigen::Matrix<double, 3, 4> p_left = calibration.Projection(left_id);
    camera_.left.fx = p_left(0, 0);
    camera_.left.fy = p_left(1, 1);
    camera_.left.cx = p_left(0, 2);
    camera_.left.cy = p_left(1, 2);
    if (extract_) {
      const std::vector<double>& size = CalibrationEntry(c, "S_rect_0" + std::to_string(left_id), 2, cam_to_cam);
      camera_.left.width = static_cast<int>(std::lround(size[0]));
      camera_.left.height = static_cast<int>(std::lround(size[1]));
      left_rectifier_ = MakeRectifier(c, left_id, cam_to_cam);
    } else {
      const cv::Mat first = internal::LoadGreyImage(left_files[0]);
      camera_.left.width = first.cols;
      camera_.left.height = first.rows;
    }
    try {
      camera_.left.Check();
    } catch (const Error& e) {
      throw Error(cam_to_cam, e.what());
    }
    stereo_ = fs::is_directory(right_dir);
    if (stereo_) {
      const Eigen::Matrix<double, 3, 4> p_right = calibration.Projection(right_id);
      // P_rect_0X = K [I | t_X] in rectified camera 00: baseline = (t_left - t_right).x.
      camera_.baseline = (p_left(0, 3) - p_right(0, 3)) / p_left(0, 0);
      RequireFile(camera_.baseline > 0, cam_to_cam, "P_rect gives a non-positive stereo baseline");
      if (extract_) right_rectifier_ = MakeRectifier(c, right_id, cam_to_cam);
    }
    // Colour beside the grey pair: sync drives only (extract drives would need their own pairing).
    color_ = !extract_ && grey && fs::is_directory(Camera(2));
    const std::vector<double> times = ReadCameraTimestamps(left_dir, left_files.size());
    std::vector<std::string> right_files;
    std::vector<double> right_times;
    if (stereo_ && extract_) {
      right_files = internal::ListImages(right_dir);
      right_times = ReadCameraTimestamps(right_dir, right_files.size());
    }
    int unpaired = 0;
    size_t j = 0;
    for (size_t i = 0; i < left_files.size(); ++i) {
      std::string right;
      if (stereo_ && extract_) {
        // Nearest right timestamp (both lists are in time order).
        while (j + 1 < right_times.size() && std::abs(right_times[j + 1] - times[i]) <= std::abs(right_times[j] - times[i])) {
          ++j;
        }
        if (!right_times.empty() && std::abs(right_times[j] - times[i]) < kMaxPairingGap) right = right_files[j];
      } else if (stereo_) {
        const std::string same_name = JoinPath(right_dir, fs::path(left_files[i]).filename().string());
        if (fs::exists(same_name)) right = same_name;
      }
      if (stereo_ && right.empty()) {
        ++unpaired;
        continue;
      }
      files_.push_back(left_files[i]);
      right_files_.push_back(right);
      timestamps_.push_back(times[i] - times[0]);
    }
    RequireFile(!files_.empty(), right_dir, "no left image has a right partner");
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
    StereoFrame frame;
    frame.index = index;
    frame.timestamp = timestamps_[index];
    if (extract_) {
      frame.left = left_rectifier_.Apply(internal::LoadGreyImage(files_[index], left_rectifier_.raw_size));
      if (options.load_right && stereo_) {
        frame.right = right_rectifier_.Apply(internal::LoadGreyImage(right_files_[index], right_rectifier_.raw_size));
      }
      return frame;
    }
    const std::string name = fs::path(files_[index]).filename().string();
    frame.left = internal::LoadGreyImage(files_[index], size);
    if (options.load_right && stereo_) frame.right = internal::LoadGreyImage(right_files_[index], size);
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
  static std::vector<double> ReadCameraTimestamps(const std::string& data_dir, size_t images) {
    const std::string path = JoinPath(fs::path(data_dir).parent_path().string(), "timestamps.txt");
    std::vector<double> times = ReadRawTimestamps(path);
    RequireFile(times.size() == images, path,
                std::to_string(times.size()) + " timestamps for " + std::to_string(images) + " images");
    return times;
  }

  std::string root_;
  std::vector<std::string> files_, right_files_;
  std::vector<double> timestamps_;
  StereoCamera camera_;
  bool stereo_ = false, color_ = false, extract_ = false;
  RawRectifier left_rectifier_, right_rectifier_;
};

}  // namespace

bool IsKittiRawDrive(const std::string& path) {
  return fs::is_directory(JoinPath(path, "image_00/data")) || fs::is_directory(JoinPath(path, "image_02/data"));
}

std::unique_ptr<SequenceReader> OpenKittiRawSequence(const std::string& path) {
  return std::make_unique<KittiRawSequence>(path);
}

}  // namespace dvso
