// KITTI raw drive reader: DRIVE/image_0X/data/*.png, image_0X/timestamps.txt,
// calibration in the drive or its date folder (calib_cam_to_cam.txt; see
// core/kitti_raw_calibration.h). The grey pair 00/01 is used when present (or
// asked for), else the colour pair 02/03 (read as grey for the odometry); beside
// the grey pair the colour images (image_02/03) are loaded on request as in the
// KITTI odometry layout.
//  - rectified ("_sync") drives: left and right images are paired by file name;
//  - unrectified ("_extract") drives: every camera is rectified on read with
//    K_0X, D_0X, R_rect_0X, P_rect_0X into S_rect_0X, and the cameras, which drop
//    frames independently, are paired by timestamp (nearest, within
//    kMaxPairingGap).
// A left frame without a partner is skipped and counted (one warning), never
// paired with a neighbour.
#include <cmath>
#include <cstdio>
#include <ctime>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_oxts.h"
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

std::string FormatKittiRawTimestamp(double epoch_seconds) {
  std::time_t whole = static_cast<std::time_t>(std::floor(epoch_seconds));
  long nanoseconds = std::lround((epoch_seconds - static_cast<double>(whole)) * 1e9);
  if (nanoseconds >= 1000000000L) ++whole, nanoseconds -= 1000000000L;
  std::tm tm{};
  gmtime_r(&whole, &tm);
  char text[64];
  std::snprintf(text, sizeof(text), "%04d-%02d-%02d %02d:%02d:%02d.%09ld", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, nanoseconds);
  return text;
}

std::vector<double> ReadKittiRawTimestamps(const std::string& path) {
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

bool IsKittiRawExtractDrive(const std::string& path) {
  return NormalizedFolderPath(path).filename().string().find("_extract") != std::string::npos;
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


// One camera of a drive: its image files, their timestamps and (extract drives) its rectifier.
struct RawCameraFiles {
  std::string dir;                  // DRIVE/image_0X/data
  std::vector<std::string> files;   // sorted
  std::vector<double> times;        // epoch seconds, one per file
  RawRectifier rectifier;           // extract drives only
};

class KittiRawSequence : public SequenceReader {
 public:
  KittiRawSequence(const std::string& root, CameraPair pair) : root_(root) {
    extract_ = IsKittiRawExtractDrive(root);
    const bool grey = fs::is_directory(Camera(0));
    const int left_id = pair == CameraPair::kColour || !grey ? 2 : 0, right_id = left_id + 1;
    RequireFile(fs::is_directory(Camera(left_id)), Camera(left_id),
                pair == CameraPair::kColour ? "no colour camera (--cameras colour needs image_02/)" : "no images");
    colour_is_left_ = left_id == 2;
    const RawCameraCalibration calibration(FindRawCalibrationDir(root));
    const std::string& cam_to_cam = calibration.path;
    const RawCameraFiles left = LoadCamera(left_id, calibration);
    const Eigen::Matrix<double, 3, 4> p_left = calibration.Projection(left_id);
    camera_.left.fx = p_left(0, 0);
    camera_.left.fy = p_left(1, 1);
    camera_.left.cx = p_left(0, 2);
    camera_.left.cy = p_left(1, 2);
    const std::vector<double>& size =
        CalibrationEntry(calibration.entries, "S_rect_0" + std::to_string(left_id), 2, cam_to_cam);
    camera_.left.width = static_cast<int>(std::lround(size[0]));
    camera_.left.height = static_cast<int>(std::lround(size[1]));
    // Sync drives hold the rectified images: of the size the calibration rectifies to, or it belongs to
    // other images (a resized download) and would give a garbage trajectory without any error.
    const cv::Size rectified(camera_.left.width, camera_.left.height);
    if (!extract_) internal::RequireImagesOfCalibratedSize(left.files, rectified, cam_to_cam);
    try {
      camera_.left.Check();
    } catch (const Error& e) {
      throw Error(cam_to_cam, e.what());
    }
    stereo_ = fs::is_directory(Camera(right_id));
    RawCameraFiles right;
    auto projection = [&](int id) -> const std::vector<double>& {
      return CalibrationEntry(calibration.entries, "P_rect_0" + std::to_string(id), 12, cam_to_cam);
    };
    if (stereo_) {
      camera_.baseline = internal::RectifiedBaseline(projection(left_id), projection(right_id), cam_to_cam);
      RequireFile(camera_.baseline > 0, cam_to_cam, "P_rect gives a non-positive stereo baseline");
      right = LoadCamera(right_id, calibration);
    }
    // The colour pair beside the grey one (for the network), paired with the grey frames like the right camera,
    // only when it was taken from the grey cameras' centres (CameraPair; the simulator's drives): on KITTI
    // cameras 02/03 sit ~6 cm beside 00/01, another viewpoint than the grey pair's maps and labels.
    RawCameraFiles colour_left, colour_right;
    // The right colour camera counts only when a right image is read at all (stereo) and its folder is there.
    const bool colour_right_read = stereo_ && fs::is_directory(Camera(3));
    // P_rect_03 is read only once the left colour camera is known to be the grey one: a calibration whose
    // colour cameras sit elsewhere needs no right colour entry for the grey pair to open.
    color_ = colour_is_left_ ||
             (fs::is_directory(Camera(2)) && internal::SameRectifiedCamera(projection(0), projection(2)) &&
              internal::ColourPairMatchesGrey(projection(0), stereo_ ? &projection(1) : nullptr, projection(2),
                                              colour_right_read ? &projection(3) : nullptr));
    if (color_ && !colour_is_left_) {
      colour_left = LoadCamera(2, calibration);
      if (colour_right_read) colour_right = LoadCamera(3, calibration);
    }
    int unpaired = 0;
    for (size_t i = 0; i < left.files.size(); ++i) {
      Frame frame;
      frame.left = left.files[i];
      if (stereo_) {
        frame.right = Partner(left, i, right);
        if (frame.right.empty()) {
          ++unpaired;
          continue;
        }
      }
      if (color_ && !colour_is_left_) {
        frame.left_colour = Partner(left, i, colour_left);
        if (!colour_right.files.empty()) frame.right_colour = Partner(left, i, colour_right);
        // Colour is optional per frame: a frame whose colour image was dropped keeps its grey pair.
        if (frame.left_colour.empty()) ++colour_missing_;
      }
      frames_.push_back(frame);
      timestamps_.push_back(left.times[i] - left.times[0]);
    }
    RequireFile(!frames_.empty(), Camera(right_id), "no left image has a right partner");
    if (unpaired > 0) {
      std::cerr << "dvso: warning: " << root << ": " << unpaired << " frame(s) without a right image skipped\n";
    }
    if (colour_missing_ > 0) {
      std::cerr << "dvso: warning: " << root << ": " << colour_missing_ << " frame(s) without a colour image\n";
    }
    left_rectifier_ = left.rectifier;
    right_rectifier_ = right.rectifier;
    colour_left_rectifier_ = colour_left.rectifier;
    colour_right_rectifier_ = colour_right.rectifier;
  }

  int size() const override { return static_cast<int>(frames_.size()); }
  bool is_stereo() const override { return stereo_; }
  std::string NotStereoReason() const override {
    return stereo_ ? "" : "no " + Camera(colour_is_left_ ? 3 : 1) + " folder";
  }
  bool has_color() const override { return color_; }
  CameraPair camera_pair() const override { return colour_is_left_ ? CameraPair::kColour : CameraPair::kGrey; }
  const StereoCamera& camera() const override { return camera_; }
  const std::vector<double>& timestamps() const override { return timestamps_; }
  const std::string& root() const override { return root_; }
  std::string FrameName(int index) const override { return fs::path(frames_.at(index).left).stem().string(); }

  StereoFrame Read(int index, const SequenceReadOptions& options) const override {
    Require(index >= 0 && index < size(), root_ + ": frame " + std::to_string(index) + " out of range");
    const Frame& files = frames_[static_cast<size_t>(index)];
    StereoFrame frame;
    frame.index = index;
    frame.timestamp = timestamps_[static_cast<size_t>(index)];
    const bool right = options.load_right && stereo_;
    if (colour_is_left_) {
      // The colour pair is the sequence: grey = its luminance, colour on request.
      const cv::Mat left_colour = LoadColour(files.left, left_rectifier_);
      cv::cvtColor(left_colour, frame.left, cv::COLOR_BGR2GRAY);
      if (options.load_color) frame.left_color = left_colour;
      if (right) {
        const cv::Mat right_colour = LoadColour(files.right, right_rectifier_);
        cv::cvtColor(right_colour, frame.right, cv::COLOR_BGR2GRAY);
        if (options.load_color) frame.right_color = right_colour;
      }
      return frame;
    }
    frame.left = LoadGrey(files.left, left_rectifier_);
    if (right) frame.right = LoadGrey(files.right, right_rectifier_);
    if (options.load_color && !files.left_colour.empty()) {
      frame.left_color = LoadColour(files.left_colour, colour_left_rectifier_);
      if (options.load_right && !files.right_colour.empty()) {
        frame.right_color = LoadColour(files.right_colour, colour_right_rectifier_);
      }
    }
    return frame;
  }

 private:
  struct Frame {
    std::string left, right, left_colour, right_colour;  // image files; "" = none
  };

  std::string Camera(int id) const { return JoinPath(JoinPath(root_, "image_0" + std::to_string(id)), "data"); }

  RawCameraFiles LoadCamera(int id, const RawCameraCalibration& calibration) const {
    RawCameraFiles camera;
    camera.dir = Camera(id);
    camera.files = internal::ListImages(camera.dir);
    RequireFile(!camera.files.empty(), camera.dir, "no images found");
    const std::string path = JoinPath(fs::path(camera.dir).parent_path().string(), "timestamps.txt");
    const std::vector<double> times = ReadKittiRawTimestamps(path);
    if (times.size() == camera.files.size()) {
      camera.times = times;
    } else {
      // Line k of timestamps.txt belongs to file k (%010d): with files missing (a damaged or partial
      // download) the remaining ones keep their own times.
      for (const std::string& file : camera.files) {
        const std::optional<long long> parsed = ParseFrameNumber(fs::path(file).stem().string());
        const size_t number = parsed ? static_cast<size_t>(*parsed) : times.size();
        RequireFile(number < times.size(), path,
                    std::to_string(times.size()) + " timestamps for " + std::to_string(camera.files.size()) +
                        " images, and " + fs::path(file).filename().string() + " has no line of its own");
        camera.times.push_back(times[number]);
      }
    }
    if (extract_) camera.rectifier = MakeRectifier(calibration.entries, id, calibration.path);
    return camera;
  }

  // The file of `other` that belongs to left frame i: the same name on sync drives; on extract
  // drives, whose cameras drop frames independently, the nearest timestamp within kMaxPairingGap.
  // "" when there is none.
  std::string Partner(const RawCameraFiles& left, size_t i, const RawCameraFiles& other) const {
    if (!extract_) {
      const std::string same_name = JoinPath(other.dir, fs::path(left.files[i]).filename().string());
      return fs::exists(same_name) ? same_name : "";
    }
    if (other.times.empty()) return "";
    const size_t best = NearestTimestamp(other.times, left.times[i]);  // the search `oxts-poses` pairs with too
    if (std::abs(other.times[best] - left.times[i]) >= kMaxPairingGap) return "";
    return other.files[best];
  }

  cv::Size RectifiedSize() const { return cv::Size(camera_.left.width, camera_.left.height); }
  cv::Mat LoadGrey(const std::string& file, const RawRectifier& rectifier) const {
    if (extract_) return rectifier.Apply(internal::LoadGreyImage(file, rectifier.raw_size));
    return internal::LoadGreyImage(file, RectifiedSize());
  }
  cv::Mat LoadColour(const std::string& file, const RawRectifier& rectifier) const {
    if (extract_) return rectifier.Apply(internal::LoadColorImage(file, rectifier.raw_size));
    return internal::LoadColorImage(file, RectifiedSize());
  }

  std::string root_;
  std::vector<Frame> frames_;
  std::vector<double> timestamps_;
  StereoCamera camera_;
  bool stereo_ = false, color_ = false, extract_ = false, colour_is_left_ = false;
  int colour_missing_ = 0;
  RawRectifier left_rectifier_, right_rectifier_, colour_left_rectifier_, colour_right_rectifier_;
};

}  // namespace

bool IsKittiRawDrive(const std::string& path) {
  return fs::is_directory(JoinPath(path, "image_00/data")) || fs::is_directory(JoinPath(path, "image_02/data"));
}

std::unique_ptr<SequenceReader> OpenKittiRawSequence(const std::string& path, CameraPair pair) {
  return std::make_unique<KittiRawSequence>(path, pair);
}

CameraPair ParseCameraPair(const std::string& name) {
  if (name == "grey" || name == "gray") return CameraPair::kGrey;
  if (name == "colour" || name == "color") return CameraPair::kColour;
  throw Error("--cameras must be grey or colour, not '" + name + "'");
}

std::string CameraPairName(CameraPair pair) { return pair == CameraPair::kColour ? "colour" : "grey"; }

std::optional<CameraPair> RecordedCameraPair(const std::string& json_path) {
  if (!std::filesystem::is_regular_file(json_path)) return std::nullopt;
  nlohmann::json j;
  try {
    std::ifstream in(json_path);
    in >> j;
  } catch (const std::exception& e) {
    throw Error(json_path, std::string("cannot parse: ") + e.what());
  }
  if (!j.is_object() || !j.contains("cameras")) return std::nullopt;
  RequireFile(j["cameras"].is_string(), json_path, "\"cameras\" must be \"grey\" or \"colour\"");
  try {
    return ParseCameraPair(j["cameras"].get<std::string>());
  } catch (const Error&) {
    throw Error(json_path, "\"cameras\" must be \"grey\" or \"colour\", not " + j["cameras"].dump());
  }
}

}  // namespace dvso
