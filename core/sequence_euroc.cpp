// EuRoC / ASL layout reader: reads intrinsics, radtan distortion and the
// cam0<->cam1 extrinsics from sensor.yaml, rectifies the pair with OpenCV, and
// exposes the same rectified stereo interface as the KITTI reader.
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "core/sequence_common.h"
#include "core/trajectory.h"

namespace dvso {

namespace fs = std::filesystem;

namespace {

struct EurocCamera {
  cv::Mat K, distortion;   // 3x3, 1x4 (k1 k2 p1 p2)
  cv::Size size;
  Eigen::Matrix4d T_body_sensor = Eigen::Matrix4d::Identity();
  std::vector<int64_t> stamps_ns;
  std::vector<std::string> files;
};

EurocCamera ReadEurocCamera(const std::string& cam_dir) {
  const std::string yaml_path = JoinPath(cam_dir, "sensor.yaml");
  RequireFile(fs::is_regular_file(yaml_path), yaml_path, "missing sensor.yaml");
  // Some EuRoC files begin with an OpenCV-style "%YAML:1.0" directive that yaml-cpp rejects.
  std::ifstream in(yaml_path);
  std::stringstream text;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("%YAML", 0) == 0) continue;
    text << line << '\n';
  }
  EurocCamera cam;
  try {
    const YAML::Node node = YAML::Load(text.str());
    const auto intrinsics = node["intrinsics"].as<std::vector<double>>();
    const auto distortion = node["distortion_coefficients"].as<std::vector<double>>();
    const auto resolution = node["resolution"].as<std::vector<int>>();
    const auto t_bs = node["T_BS"]["data"].as<std::vector<double>>();
    RequireFile(intrinsics.size() == 4, yaml_path, "intrinsics needs fu fv cu cv");
    RequireFile(distortion.size() == 4, yaml_path, "distortion_coefficients needs k1 k2 p1 p2");
    RequireFile(resolution.size() == 2, yaml_path, "resolution needs width height");
    RequireFile(t_bs.size() == 16, yaml_path, "T_BS data needs 16 numbers");
    if (node["distortion_model"]) {
      const std::string model = node["distortion_model"].as<std::string>();
      RequireFile(model == "radial-tangential" || model == "radtan", yaml_path,
                  "distortion model '" + model + "' is not supported (radial-tangential only)");
    }
    cam.K = (cv::Mat_<double>(3, 3) << intrinsics[0], 0, intrinsics[2], 0, intrinsics[1], intrinsics[3], 0, 0, 1);
    cam.distortion = (cv::Mat_<double>(1, 4) << distortion[0], distortion[1], distortion[2], distortion[3]);
    cam.size = cv::Size(resolution[0], resolution[1]);
    for (int i = 0; i < 16; ++i) cam.T_body_sensor(i / 4, i % 4) = t_bs[i];
  } catch (const YAML::Exception& e) {
    throw Error(yaml_path, std::string("cannot parse: ") + e.what());
  }
  const std::string csv_path = JoinPath(cam_dir, "data.csv");
  std::ifstream csv(csv_path);
  RequireFile(csv.good(), csv_path, "cannot open data.csv");
  int line_number = 0;
  while (std::getline(csv, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    const auto comma = line.find(',');
    RequireFile(comma != std::string::npos, csv_path,
                "line " + std::to_string(line_number) + ": expected 'timestamp,filename'");
    std::string file = line.substr(comma + 1);
    while (!file.empty() && (file.back() == '\r' || file.back() == ' ')) file.pop_back();
    try {
      cam.stamps_ns.push_back(std::stoll(line.substr(0, comma)));
    } catch (const std::exception&) {
      throw Error(csv_path, "line " + std::to_string(line_number) + ": bad timestamp");
    }
    cam.files.push_back(JoinPath(JoinPath(cam_dir, "data"), file));
  }
  RequireFile(!cam.files.empty(), csv_path, "no frames listed");
  internal::RequireImagesOfCalibratedSize(cam.files, cam.size, yaml_path);
  return cam;
}

// Intrinsics from the upper-left 3x3 of a camera or projection matrix (CV_64F).
PinholeCamera PinholeFromMatrix(const cv::Mat& K, const cv::Size& size) {
  PinholeCamera c;
  c.fx = K.at<double>(0, 0);
  c.fy = K.at<double>(1, 1);
  c.cx = K.at<double>(0, 2);
  c.cy = K.at<double>(1, 2);
  c.width = size.width;
  c.height = size.height;
  return c;
}

class EurocSequence : public SequenceReader {
 public:
  explicit EurocSequence(const std::string& root) : root_(root) {
    const std::string mav = fs::is_directory(JoinPath(root, "mav0")) ? JoinPath(root, "mav0") : root;
    const EurocCamera cam0 = ReadEurocCamera(JoinPath(mav, "cam0"));
    size0_ = cam0.size;
    if (!fs::is_directory(JoinPath(mav, "cam1"))) {
      InitializeMonocular(cam0);
      return;
    }
    const EurocCamera cam1 = ReadEurocCamera(JoinPath(mav, "cam1"));
    // Pair frames by timestamp (nearest within 2 ms; EuRoC stamps are identical).
    size_t j = 0;
    int unpaired = 0;
    for (size_t i = 0; i < cam0.stamps_ns.size(); ++i) {
      while (j + 1 < cam1.stamps_ns.size() &&
             std::llabs(cam1.stamps_ns[j + 1] - cam0.stamps_ns[i]) <= std::llabs(cam1.stamps_ns[j] - cam0.stamps_ns[i])) {
        ++j;
      }
      if (std::llabs(cam1.stamps_ns[j] - cam0.stamps_ns[i]) <= 2000000) {
        left_files_.push_back(cam0.files[i]);
        right_files_.push_back(cam1.files[j]);
        timestamps_.push_back(cam0.stamps_ns[i] * 1e-9);
      } else {
        ++unpaired;
      }
    }
    RequireFile(!left_files_.empty(), mav, "no cam0/cam1 frames share a timestamp");
    if (unpaired > 0) {
      std::cerr << "dvso: warning: " << mav << ": " << unpaired
                << " cam0 frame(s) without a cam1 frame within 2 ms skipped\n";
    }
    // Relative pose: p_c1 = R p_c0 + T.
    const Eigen::Matrix4d T_c1_c0 = cam1.T_body_sensor.inverse() * cam0.T_body_sensor;
    cv::Mat R(3, 3, CV_64F), T(3, 1, CV_64F);
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) R.at<double>(r, c) = T_c1_c0(r, c);
      T.at<double>(r) = T_c1_c0(r, 3);
    }
    cv::Mat R1, R2, P1, P2, Q;
    cv::stereoRectify(cam0.K, cam0.distortion, cam1.K, cam1.distortion, cam0.size, R, T, R1, R2, P1, P2, Q,
                      cv::CALIB_ZERO_DISPARITY, 0.0, cam0.size);
    cv::initUndistortRectifyMap(cam0.K, cam0.distortion, R1, P1, cam0.size, CV_32FC1, map0x_, map0y_);
    cv::initUndistortRectifyMap(cam1.K, cam1.distortion, R2, P2, cam1.size, CV_32FC1, map1x_, map1y_);
    camera_.left = PinholeFromMatrix(P1, cam0.size);
    camera_.baseline = -P2.at<double>(0, 3) / P2.at<double>(0, 0);
    RequireFile(camera_.baseline > 0, mav, "cam1 is not to the right of cam0 after rectification");
    size0_ = cam0.size;
    size1_ = cam1.size;
  }

  int size() const override { return static_cast<int>(left_files_.size()); }
  bool is_stereo() const override { return !right_files_.empty(); }
  bool has_color() const override { return false; }
  const StereoCamera& camera() const override { return camera_; }
  const std::vector<double>& timestamps() const override { return timestamps_; }
  const std::string& root() const override { return root_; }
  std::string FrameName(int index) const override {
    return std::filesystem::path(left_files_.at(index)).stem().string();
  }

  StereoFrame Read(int index, const SequenceReadOptions& options) const override {
    Require(index >= 0 && index < size(), root_ + ": frame " + std::to_string(index) + " out of range");
    StereoFrame frame;
    frame.index = index;
    frame.timestamp = timestamps_[index];
    cv::remap(internal::LoadGreyImage(left_files_[index], size0_), frame.left, map0x_, map0y_, cv::INTER_LINEAR);
    if (options.load_right && is_stereo()) {
      cv::remap(internal::LoadGreyImage(right_files_[index], size1_), frame.right, map1x_, map1y_,
                cv::INTER_LINEAR);
    }
    return frame;
  }

 private:
  // cam0 only (monocular use, e.g. DVSO): undistorted with the same focal
  // length, no baseline.
  void InitializeMonocular(const EurocCamera& cam0) {
    left_files_ = cam0.files;
    for (const int64_t ns : cam0.stamps_ns) timestamps_.push_back(ns * 1e-9);
    RequireFile(!left_files_.empty(), root_, "no cam0 frames");
    // Without distortion the intrinsics stay; with it, the valid-pixels-only camera (alpha 0).
    const cv::Mat K = cv::norm(cam0.distortion) == 0.0
                          ? cv::Mat(cam0.K.clone())
                          : cv::getOptimalNewCameraMatrix(cam0.K, cam0.distortion, cam0.size, 0.0, cam0.size);
    cv::initUndistortRectifyMap(cam0.K, cam0.distortion, cv::Mat(), K, cam0.size, CV_32FC1, map0x_, map0y_);
    camera_.left = PinholeFromMatrix(K, cam0.size);
    camera_.baseline = 0;
  }

  std::string root_;
  std::vector<std::string> left_files_, right_files_;
  std::vector<double> timestamps_;
  StereoCamera camera_;
  cv::Size size0_, size1_;
  cv::Mat map0x_, map0y_, map1x_, map1y_;
};

class ImageFolderSequence : public SequenceReader {
 public:
  ImageFolderSequence(const std::string& root, const std::string& camera_file) : root_(root) {
    files_ = internal::ListImages(root);
    RequireFile(!files_.empty(), root, "no images found");
    camera_.left = ReadDsoCameraFile(camera_file);
    camera_.baseline = 0.0;
    internal::RequireImagesOfCalibratedSize(files_, cv::Size(camera_.left.width, camera_.left.height), camera_file);
    const std::string times = JoinPath(root, "times.txt");
    if (fs::is_regular_file(times)) {
      timestamps_ = ReadTimes(times);
      RequireFile(timestamps_.size() == files_.size(), times, "timestamp count differs from image count");
    } else {
      for (size_t i = 0; i < files_.size(); ++i) timestamps_.push_back(0.1 * i);
    }
  }
  int size() const override { return static_cast<int>(files_.size()); }
  bool is_stereo() const override { return false; }
  std::string NotStereoReason() const override { return "an image folder is one camera"; }
  bool has_color() const override { return false; }
  const StereoCamera& camera() const override { return camera_; }
  const std::vector<double>& timestamps() const override { return timestamps_; }
  const std::string& root() const override { return root_; }
  std::string FrameName(int index) const override {
    return std::filesystem::path(files_.at(index)).stem().string();
  }
  StereoFrame Read(int index, const SequenceReadOptions&) const override {
    Require(index >= 0 && index < size(), root_ + ": frame " + std::to_string(index) + " out of range");
    StereoFrame frame;
    frame.index = index;
    frame.timestamp = timestamps_[index];
    frame.left = internal::LoadGreyImage(files_[index], cv::Size(camera_.left.width, camera_.left.height));
    return frame;
  }

 private:
  std::string root_;
  std::vector<std::string> files_;
  StereoCamera camera_;
  std::vector<double> timestamps_;
};

}  // namespace

std::unique_ptr<SequenceReader> OpenEurocSequence(const std::string& path) {
  return std::make_unique<EurocSequence>(path);
}

std::unique_ptr<SequenceReader> OpenImageFolder(const std::string& path, const std::string& camera_file) {
  return std::make_unique<ImageFolderSequence>(path, camera_file);
}

std::unique_ptr<SequenceReader> OpenSequence(const std::string& path, const std::string& camera_file,
                                             CameraPair pair) {
  RequireFile(fs::is_directory(path), path, "sequence directory does not exist");
  // Layouts with their own calibration: a camera file given for them would be silently ignored.
  const auto require_no_camera_file = [&](const char* layout) {
    RequireFile(camera_file.empty(), path,
                std::string("is a ") + layout + " with its own calibration: --camera FILE is for image folders only");
  };
  if (IsKittiRawDrive(path)) {
    require_no_camera_file("KITTI raw drive");
    return OpenKittiRawSequence(path, pair);
  }
  if (fs::is_regular_file(JoinPath(path, "calib.txt"))) {
    require_no_camera_file("KITTI odometry sequence");
    return OpenKittiSequence(path, pair);
  }
  RequireFile(pair == CameraPair::kGrey, path,
              "--cameras colour needs a KITTI layout (image_2/ image_3/ of an odometry folder, image_02/ image_03/ of a raw drive)");
  if (fs::is_directory(JoinPath(path, "mav0")) || fs::is_regular_file(JoinPath(path, "cam0/data.csv"))) {
    require_no_camera_file("EuRoC sequence");
    return OpenEurocSequence(path);
  }
  if (!camera_file.empty()) return OpenImageFolder(path, camera_file);
  throw Error(path, "unknown sequence layout: expected calib.txt (KITTI), image_00/data (KITTI raw), mav0/ (EuRoC), or an image folder "
                    "with --camera FILE");
}

}  // namespace dvso
