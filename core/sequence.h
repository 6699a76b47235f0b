// Streaming readers for rectified stereo (or monocular) image sequences. A
// reader never holds the whole sequence in memory: Read(i) loads frame i.
//
// Layouts:
//  - KITTI odometry: image_0/ image_1/ (grey), image_2/ image_3/ (colour,
//    optional), calib.txt (P0..P3), times.txt; frame i = %06d.png. Our
//    simulator writes this layout too (plus poses.txt, depth_0/, disp_0/, disp_1/).
//  - EuRoC/ASL: mav0/cam{0,1}/data.csv + sensor.yaml; rectified on read.
//  - KITTI raw drives: image_00..03/data/, timestamps.txt, calibration files of
//    the date folder; _sync drives as they are, _extract drives rectified on read
//    (sequence_kitti_raw.cpp).
//  - Monocular folder: images (sorted by name) + a DSO-style camera file.
#pragma once

#include <algorithm>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"

namespace dvso {

// Which stereo pair of a KITTI layout (raw drive or odometry folder) is the sequence's left/right pair:
// the grey cameras 00/01 (odometry and labels) or the colour cameras 02/03 (read as grey for the odometry,
// as colour for the network). Colour images are offered beside the grey pair (has_color) only when they
// were taken from the grey cameras' centres (the simulator's sequences): on KITTI they are another
// viewpoint 6 cm away, and a map or label made on one pair is misplaced by ~12 % of its disparity on the other.
enum class CameraPair { kGrey, kColour };

struct StereoFrame {
  int index = 0;          // 0-based position in the sequence
  double timestamp = 0;   // seconds
  cv::Mat left;           // CV_8UC1, rectified
  cv::Mat right;          // CV_8UC1, rectified; empty for monocular sequences
  cv::Mat left_color;     // CV_8UC3 (BGR) when the sequence has colour, else empty
  cv::Mat right_color;    // CV_8UC3 (BGR) when the sequence has colour, else empty
};

struct SequenceReadOptions {
  bool load_right = true;   // load the right image (stereo); off for monocular use
  bool load_color = false;  // also load colour images when present
};

class SequenceReader {
 public:
  virtual ~SequenceReader() = default;
  virtual int size() const = 0;
  virtual bool is_stereo() const = 0;
  // Why is_stereo() is false, for the error of a command that needs a pair ("" when stereo).
  virtual std::string NotStereoReason() const { return is_stereo() ? "" : "no right camera"; }
  virtual bool has_color() const = 0;
  // The KITTI camera pair the frames come from: the one asked for, or colour 02/03 where a folder has no
  // grey cameras (outputs record it; labels / maps of another pair are refused). Grey for other layouts.
  virtual CameraPair camera_pair() const { return CameraPair::kGrey; }
  // Rectified intrinsics (and baseline for stereo; 0 for monocular).
  virtual const StereoCamera& camera() const = 0;
  // Timestamps of all frames (seconds), size() entries.
  virtual const std::vector<double>& timestamps() const = 0;
  // Loads frame i; throws dvso::Error naming the file on any problem
  // (missing/unreadable image, size different from the calibration).
  virtual StereoFrame Read(int index, const SequenceReadOptions& options = {}) const = 0;
  // Directory the sequence was opened from.
  virtual const std::string& root() const = 0;
  // Name of frame i's (left) image file without folder and extension, e.g.
  // "000042" in the KITTI layout; per-frame outputs and inputs (disparity
  // maps) are named after it.
  virtual std::string FrameName(int index) const = 0;
};

// One past the last frame of a run over frames [first, first + count) of a sequence of `size` frames;
// count < 0 = to the end. Never past the end, and no int overflow for a huge count. Requires first < size.
inline int RunEndFrame(int size, int first, int count) {
  return count < 0 ? size : first + std::min(size - first, count);
}

// The warning for a count that runs past the end (the run is clamped, as RunEndFrame does), or "" when
// the frames asked for all exist: a user who typed --count 5000 on a 4541-frame sequence is told so.
inline std::string CountPastEndWarning(int size, int first, int count) {
  if (count < 0 || count <= size - first) return "";
  return "dvso: warning: --count " + std::to_string(count) + " from frame " + std::to_string(first) +
         " goes past the end of the sequence (" + std::to_string(size) + " frames): running " +
         std::to_string(size - first) + " frames";
}

// "grey" | "colour" (also "gray", "color"); throws dvso::Error otherwise.
CameraPair ParseCameraPair(const std::string& name);
// "grey" | "colour": the name outputs record (labels_summary.json, prediction_info.json).
std::string CameraPairName(CameraPair pair);
// The pair an output records in its JSON file ("cameras": "grey" | "colour"; labels_summary.json,
// prediction_info.json): nullopt when the file does not exist or records none (written before outputs
// named their pair). Throws dvso::Error naming the file when it cannot be parsed or names another value.
std::optional<CameraPair> RecordedCameraPair(const std::string& json_path);

// Opens a sequence, detecting the layout: KITTI (calib.txt), EuRoC (mav0/ or
// cam0/data.csv), or a monocular folder (needs camera_file). `pair` chooses the
// cameras of a KITTI layout; kColour on any other layout is an error. Throws dvso::Error.
std::unique_ptr<SequenceReader> OpenSequence(const std::string& path, const std::string& camera_file = "",
                                             CameraPair pair = CameraPair::kGrey);

std::unique_ptr<SequenceReader> OpenKittiSequence(const std::string& path, CameraPair pair = CameraPair::kGrey);
// KITTI raw drive, _sync or _extract (DRIVE/image_0X/data/, calibration in DRIVE or its parent).
std::unique_ptr<SequenceReader> OpenKittiRawSequence(const std::string& path, CameraPair pair = CameraPair::kGrey);
bool IsKittiRawDrive(const std::string& path);
// "2011-09-26 13:02:25.964389445" (KITTI raw timestamps.txt) -> seconds since the epoch, UTC.
double ParseKittiRawTimestamp(const std::string& text, const std::string& path);
// Every line of a raw drive's timestamps.txt (image_0X/, velodyne_points/, oxts/) in seconds since the epoch;
// line k belongs to file k. Throws naming the file.
std::vector<double> ReadKittiRawTimestamps(const std::string& path);
// Whether a raw drive folder is an unsynced `_extract` one (distorted images, streams numbered on their own,
// OXTS at 100 Hz) rather than a `_sync` one (rectified, one file per frame in every stream).
bool IsKittiRawExtractDrive(const std::string& path);
// Seconds since the epoch (UTC) -> "2011-09-26 13:02:25.964389445", the inverse of the above.
std::string FormatKittiRawTimestamp(double epoch_seconds);
std::unique_ptr<SequenceReader> OpenEurocSequence(const std::string& path);
std::unique_ptr<SequenceReader> OpenImageFolder(const std::string& path, const std::string& camera_file);

// Parses a KITTI calib.txt for one stereo pair: the grey pair takes its intrinsics from P0 and its
// baseline from P1 (baseline = -(P1[0][3] - P0[0][3]) / P1[0][0]), the colour pair from P2 and P3 the
// same way (on KITTI 0.532 m against the grey 0.537 m). Image size is taken from the images by the caller.
StereoCamera ReadKittiCalibration(const std::string& calib_path, int width, int height,
                                  CameraPair pair = CameraPair::kGrey);
// Whether calib.txt's colour cameras (P2, P3) are the grey ones (P0, P1) in colour, as in the simulator's
// sequences, rather than another viewpoint (KITTI: 6 cm beside them).
bool KittiColourMatchesGrey(const std::string& calib_path);
void WriteKittiCalibration(const std::string& calib_path, const StereoCamera& camera);
// `camera` as ReadKittiCalibration reads it back from the calib.txt WriteKittiCalibration writes for it
// (12 significant digits): what a reader of a simulated sequence will see, known before it is written.
StereoCamera KittiCalibrationAsReadBack(const StereoCamera& camera);

}  // namespace dvso
