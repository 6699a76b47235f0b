// KITTI odometry layout reader (also what `dvso simulate` writes).
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/sequence.h"
#include "core/sequence_common.h"
#include "core/trajectory.h"

namespace dvso {

namespace fs = std::filesystem;

namespace {

// Every "NAME: numbers" line of a calib.txt read from `in` (`calib_path` names it in errors); P0..P3
// must have 12 numbers. Blank lines and '#' comments are skipped, a UTF-8 byte order mark and blanks
// around the name are ignored (files written by other tools).
std::map<std::string, std::vector<double>> ParseCalibrationRows(std::istream& in, const std::string& calib_path) {
  std::map<std::string, std::vector<double>> rows;
  std::string line;
  int line_number = 0;
  constexpr const char* kBlanks = " \t\r";
  constexpr const char* kUtf8ByteOrderMark = "\xEF\xBB\xBF";
  while (std::getline(in, line)) {
    ++line_number;
    if (line_number == 1 && line.rfind(kUtf8ByteOrderMark, 0) == 0) line.erase(0, 3);
    const auto first = line.find_first_not_of(kBlanks);
    if (first == std::string::npos || line[first] == '#') continue;
    const auto colon = line.find(':');
    RequireFile(colon != std::string::npos, calib_path,
                "line " + std::to_string(line_number) + ": expected 'NAME: values'");
    std::string name = line.substr(0, colon);
    name.erase(0, name.find_first_not_of(kBlanks));
    name.erase(name.find_last_not_of(kBlanks) + 1);
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
  return rows;
}

std::map<std::string, std::vector<double>> ReadCalibrationRows(const std::string& calib_path) {
  std::ifstream in(calib_path);
  RequireFile(in.good(), calib_path, "cannot open calibration file");
  return ParseCalibrationRows(in, calib_path);
}

// The text WriteKittiCalibration writes: the grey pair (0, 1) and the colour pair (2, 3) share the
// rectified geometry (the simulator renders both views of each pair from one camera).
std::string KittiCalibrationText(const StereoCamera& camera) {
  std::ostringstream out;
  out << std::scientific << std::setprecision(12);
  const auto& c = camera.left;
  for (int i = 0; i < 4; ++i) {
    const double tx = (i % 2 == 1) ? -c.fx * camera.baseline : 0.0;
    out << "P" << i << ": " << c.fx << " 0 " << c.cx << " " << tx << " 0 " << c.fy << " " << c.cy << " 0 0 0 1 0\n";
  }
  return out.str();
}

StereoCamera CameraFromCalibrationRows(std::map<std::string, std::vector<double>> rows, const std::string& calib_path,
                                       int width, int height, CameraPair pair) {
  const bool colour = pair == CameraPair::kColour;
  const std::string left_key = colour ? "P2" : "P0", right_key = colour ? "P3" : "P1";
  RequireFile(rows.count(left_key) == 1, calib_path,
              "missing " + left_key + " line" + (colour ? " (the colour pair image_2/image_3 needs P2 and P3)" : ""));
  const auto& p_left = rows[left_key];
  StereoCamera camera;
  camera.left.fx = p_left[0];
  camera.left.fy = p_left[5];
  camera.left.cx = p_left[2];
  camera.left.cy = p_left[6];
  camera.left.width = width;
  camera.left.height = height;
  camera.baseline = 0.0;
  if (rows.count(right_key) == 1) {
    const auto& p_right = rows[right_key];
    RequireFile(p_right[0] > 0, calib_path, right_key + " has a non-positive focal length");
    camera.baseline = internal::RectifiedBaseline(p_left, p_right, calib_path);
    RequireFile(camera.baseline > 0, calib_path, right_key + " gives a non-positive stereo baseline");
  }
  try {
    camera.left.Check();
  } catch (const Error& e) {
    throw Error(calib_path, e.what());
  }
  return camera;
}

}  // namespace

StereoCamera ReadKittiCalibration(const std::string& calib_path, int width, int height, CameraPair pair) {
  return CameraFromCalibrationRows(ReadCalibrationRows(calib_path), calib_path, width, height, pair);
}

StereoCamera KittiCalibrationAsReadBack(const StereoCamera& camera) {
  std::istringstream text(KittiCalibrationText(camera));
  return CameraFromCalibrationRows(ParseCalibrationRows(text, "calib.txt"), "calib.txt", camera.left.width,
                                   camera.left.height, CameraPair::kGrey);
}

bool KittiColourMatchesGrey(const std::string& calib_path) {
  std::map<std::string, std::vector<double>> rows = ReadCalibrationRows(calib_path);
  if (!rows.count("P0") || !rows.count("P2")) return false;
  const auto row = [&](const char* key) { return rows.count(key) ? &rows.at(key) : nullptr; };
  return internal::ColourPairMatchesGrey(rows["P0"], row("P1"), rows["P2"], row("P3"));
}

void WriteKittiCalibration(const std::string& calib_path, const StereoCamera& camera) {
  WriteStreamAtomically(calib_path, [&](std::ostream& out) { out << KittiCalibrationText(camera); });
}

namespace {

class KittiSequence : public SequenceReader {
 public:
  KittiSequence(const std::string& root, CameraPair pair) : root_(root) {
    const std::string calib = JoinPath(root, "calib.txt");
    RequireFile(fs::is_regular_file(calib), calib, "missing calibration file (KITTI layout needs calib.txt)");
    const bool has_grey = fs::is_directory(JoinPath(root, "image_0"));
    const bool has_colour = fs::is_directory(JoinPath(root, "image_2"));
    // The grey pair unless the colour one is asked for or is all there is (colour-only download):
    // then image_2/image_3 are read as grey for the odometry, with their own calibration P2/P3.
    const bool colour_is_left = pair == CameraPair::kColour || !has_grey;
    RequireFile(!colour_is_left || has_colour, JoinPath(root, "image_2"),
                has_grey ? "no colour camera (--cameras colour needs image_2/)" : "no image_0/ or image_2/ folder");
    pair_ = colour_is_left ? CameraPair::kColour : CameraPair::kGrey;
    left_dir_ = JoinPath(root, colour_is_left ? "image_2" : "image_0");
    right_dir_ = JoinPath(root, colour_is_left ? "image_3" : "image_1");
    files_ = internal::ListImages(left_dir_);
    RequireFile(!files_.empty(), left_dir_, "no images found");
    const cv::Size size = internal::FirstDecodableImageSize(files_);
    camera_ = ReadKittiCalibration(calib, size.width, size.height,
                                   colour_is_left ? CameraPair::kColour : CameraPair::kGrey);
    internal::CheckPrincipalPointFitsImages(camera_.left.cx, camera_.left.cy, size.width, size.height, calib);
    const std::string right_folder = fs::path(right_dir_).filename().string() + "/";
    const auto right_of = [&](size_t i) { return JoinPath(right_dir_, fs::path(files_[i]).filename().string()); };
    if (camera_.baseline <= 0) {
      not_stereo_reason_ = calib + " has no " + (colour_is_left ? "P3" : "P1") + " line";
    } else if (!fs::is_directory(right_dir_)) {
      not_stereo_reason_ = "no " + right_folder + " folder";
    } else {
      // A right folder that holds none of the first left names (other names, another format, emptied)
      // would fail every frame of a stereo run, one warning at a time; a few missing right images are
      // lost frames of the run, each said.
      const size_t probes = std::min(files_.size(), static_cast<size_t>(internal::kSizeProbeFrames));
      bool any_right = false;
      for (size_t i = 0; i < probes && !any_right; ++i) any_right = fs::exists(right_of(i));
      if (!any_right) {
        not_stereo_reason_ = right_of(0) + " is missing, and so are the next " + std::to_string(probes - 1) +
                             " (the right images must carry the left ones' names)";
      }
    }
    stereo_ = not_stereo_reason_.empty();
    // Colour beside the grey pair only when it was taken from the same centres (CameraPair), and only when
    // image_2/ holds images: an emptied folder (left by an earlier colour run, or by hand) is no colour
    // camera, and taking it for one fails on image_2/<first frame> in every colour reader.
    color_ = colour_is_left ||
             (has_colour && KittiColourMatchesGrey(calib) && !internal::ListImages(JoinPath(root, "image_2")).empty());
    const std::string times = JoinPath(root, "times.txt");
    const bool has_times = fs::is_regular_file(times);
    if (has_times) timestamps_ = ReadTimes(times);
    // Frame i is image i: a missing image would shift every later frame onto another time and pose.
    const std::string missing = internal::FirstMissingNumberedFrame(files_, timestamps_.size());
    if (!missing.empty()) {
      RequireFile(!has_times, missing, "missing (times.txt has " + std::to_string(timestamps_.size()) +
                                           " frames; frame i is image i): restore it, or renumber the images and times");
      std::cerr << "dvso: warning: " << missing << " is missing: the frames are taken in file order, so every later "
                << "frame is one earlier than its number (poses and times of its number do not apply)" << std::endl;
    }
    if (has_times) {
      RequireFile(timestamps_.size() == files_.size(), times,
                  "has " + std::to_string(timestamps_.size()) + " timestamps for " +
                      std::to_string(files_.size()) + " images");
    } else {
      for (size_t i = 0; i < files_.size(); ++i) timestamps_.push_back(0.1 * i);
    }
  }

  int size() const override { return static_cast<int>(files_.size()); }
  bool is_stereo() const override { return stereo_; }
  std::string NotStereoReason() const override { return not_stereo_reason_; }
  bool has_color() const override { return color_; }
  CameraPair camera_pair() const override { return pair_; }
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
  std::string not_stereo_reason_;  // NotStereoReason()
  CameraPair pair_ = CameraPair::kGrey;  // the pair read (colour where there are no grey images)
  std::vector<double> timestamps_;
};

}  // namespace

std::unique_ptr<SequenceReader> OpenKittiSequence(const std::string& path, CameraPair pair) {
  return std::make_unique<KittiSequence>(path, pair);
}

}  // namespace dvso
