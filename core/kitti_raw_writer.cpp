#include "core/kitti_raw_writer.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/image_file.h"
#include "core/kitti_oxts.h"
#include "core/kitti_velodyne.h"
#include "core/progress.h"
#include "core/sequence.h"
#include "core/trajectory.h"

namespace dvso {

namespace fs = std::filesystem;

namespace {

constexpr double kDegToRad = M_PI / 180.0;
// HDL-64E vertical field of view (the KITTI scanner): beams spread evenly between these elevations.
constexpr double kTopBeamElevationDeg = 2.0;
constexpr double kBottomBeamElevationDeg = -24.9;
// A ray whose direction in the camera has z below this (cos of ~84 deg) is treated as outside the view.
constexpr double kMinViewCosine = 0.1;
constexpr int kRawNameDigits = 10;

Eigen::Isometry3d Rigid(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

std::string RawName(int index, const std::string& extension) {
  return FrameFileName(index, extension, kRawNameDigits);
}

// Removes the frame files (%010d.png/.bin/.txt) of `dir` left by an earlier, longer (or colour) run into
// the same drive folder: a reader would take them for frames of this one.
void RemoveFrameFiles(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) return;
  std::vector<fs::path> stale;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string stem = entry.path().stem().string();
    const std::string ext = entry.path().extension().string();
    const bool numbered = stem.size() == kRawNameDigits &&
                          stem.find_first_not_of("0123456789") == std::string::npos;
    if (entry.is_regular_file() && numbered && (ext == ".png" || ext == ".bin" || ext == ".txt")) {
      stale.push_back(entry.path());
    }
  }
  for (const fs::path& path : stale) fs::remove(path);
}

std::string TextOf(const std::function<void(std::ostream&)>& body) {
  std::ostringstream out;
  out << std::setprecision(17);
  body(out);
  return out.str();
}

void WriteText(const std::string& path, const std::string& text) {
  WriteStreamAtomically(path, [&](std::ostream& out) { out << text; });
}

void WriteText(const std::string& path, const std::function<void(std::ostream&)>& body) {
  WriteText(path, TextOf(body));
}

std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void WritePng(const std::string& path, const cv::Mat& image) {
  WriteImageAtomically(path, image, {cv::IMWRITE_PNG_COMPRESSION, 1});
}

void WriteRigid(std::ostream& out, const Eigen::Isometry3d& T) {
  out << "calib_time: 25-May-2012 16:47:16\nR:";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out << ' ' << T.linear()(r, c);
  out << "\nT: " << T.translation().x() << ' ' << T.translation().y() << ' ' << T.translation().z() << '\n';
}

template <typename Matrix>
void WriteEntry(std::ostream& out, const std::string& key, const Matrix& m) {
  out << key << ":";
  for (int r = 0; r < m.rows(); ++r)
    for (int c = 0; c < m.cols(); ++c) out << ' ' << m(r, c);
  out << '\n';
}

// The geometry of one camera of the drive.
struct RawCamera {
  Eigen::Matrix3d K_rect;           // P_rect_0X's left 3x3 (the simulated intrinsics)
  double tx = 0.0;                  // P_rect_0X(0, 3) = -fx * offset along x
  Eigen::Matrix3d K_raw;            // K_0X of the unrectified camera (extract)
  cv::Size rect_size, raw_size;
};

cv::Mat ToCv(const Eigen::Matrix3d& m) {
  cv::Mat out(3, 3, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out.at<double>(r, c) = m(r, c);
  return out;
}

// calib_cam_to_cam.txt for cameras 00..03 (grey left/right, colour at the same centres).
std::string CamToCamText(const RawCamera& left, const RawCamera& right, const KittiRawRig& rig,
                         const std::vector<double>& distortion, double baseline) {
  return TextOf([&](std::ostream& out) {
    out << "calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\n";
    for (int id = 0; id < 4; ++id) {
      const RawCamera& cam = id % 2 == 0 ? left : right;
      const std::string x = "_0" + std::to_string(id);
      out << "S" << x << ": " << cam.raw_size.width << ' ' << cam.raw_size.height << '\n';
      WriteEntry(out, "K" + x, cam.K_raw);
      out << "D" << x << ":";
      for (double d : distortion) out << ' ' << d;
      out << '\n';
      // R_0X, T_0X: camera 0X relative to camera 00 (unrectified), the devkit's extrinsics.
      const Eigen::Vector3d t(id % 2 == 0 ? 0.0 : -baseline, 0.0, 0.0);
      WriteEntry(out, "R" + x, Eigen::Matrix3d::Identity());
      WriteEntry(out, "T" + x, (rig.rect_from_cam0.transpose() * t).transpose());
      out << "S_rect" << x << ": " << cam.rect_size.width << ' ' << cam.rect_size.height << '\n';
      WriteEntry(out, "R_rect" + x, rig.rect_from_cam0);
      Eigen::Matrix<double, 3, 4> P = Eigen::Matrix<double, 3, 4>::Zero();
      P.leftCols<3>() = cam.K_rect;
      P(0, 3) = cam.tx;
      WriteEntry(out, "P_rect" + x, P);
    }
  });
}

// The calibration files of a date folder are read by every drive of that date: one that exists
// with other contents is replaced only when it belongs to nothing but this simulated drive (the
// drive folder carries kSimulatedDriveMarker and no other drive of the date exists). A real KITTI
// date folder, or another simulated drive with another camera, keeps its calibration.
void RequireCalibrationReplaceable(const std::string& date_dir, const std::string& drive_name, bool drive_is_simulated,
                                   const std::vector<std::pair<std::string, std::string>>& calibration) {
  namespace fs = std::filesystem;
  std::string changed;  // the first calibration file this drive would change
  for (const auto& [path, text] : calibration) {
    if (fs::exists(path) && ReadWholeFile(path) != text) {
      changed = path;
      break;
    }
  }
  if (changed.empty()) return;
  std::string other_drives;
  if (fs::is_directory(date_dir)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(date_dir)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_directory() && name != drive_name && name.find("_drive_") != std::string::npos) {
        other_drives += (other_drives.empty() ? "" : ", ") + name;
      }
    }
  }
  RequireFile(drive_is_simulated && other_drives.empty(), changed,
              "exists with another calibration" +
                  (other_drives.empty() ? std::string(" and no simulated drive of this date owns it")
                                        : " that the drive(s) " + other_drives + " read") +
                  "; not replaced: choose another --raw-out");
}

// Raw (distorted, unrectified) pixel -> rectified pixel of one camera: the map that warps a
// rectified image into the raw one. Throws when the rectified image does not lie inside the raw one.
struct DistortionWarp {
  cv::Mat map_x, map_y;
};

DistortionWarp MakeDistortionWarp(const RawCamera& cam, const KittiRawRig& rig, const std::vector<double>& distortion) {
  const cv::Mat K_raw = ToCv(cam.K_raw), K_rect = ToCv(cam.K_rect), R = ToCv(rig.rect_from_cam0);
  cv::Mat D(1, 5, CV_64F);
  for (int i = 0; i < 5; ++i) D.at<double>(0, i) = distortion[i];
  std::vector<cv::Point2f> raw_pixels;
  raw_pixels.reserve(static_cast<size_t>(cam.raw_size.area()));
  for (int v = 0; v < cam.raw_size.height; ++v)
    for (int u = 0; u < cam.raw_size.width; ++u) raw_pixels.emplace_back(static_cast<float>(u), static_cast<float>(v));
  std::vector<cv::Point2f> rect_pixels;
  cv::undistortPoints(raw_pixels, rect_pixels, K_raw, D, R, K_rect);
  DistortionWarp warp;
  warp.map_x.create(cam.raw_size, CV_32F);
  warp.map_y.create(cam.raw_size, CV_32F);
  for (size_t i = 0; i < raw_pixels.size(); ++i) {
    const int u = static_cast<int>(raw_pixels[i].x), v = static_cast<int>(raw_pixels[i].y);
    warp.map_x.at<float>(v, u) = rect_pixels[i].x;
    warp.map_y.at<float>(v, u) = rect_pixels[i].y;
  }
  // The reader's direction: every rectified pixel must come from inside the raw image.
  cv::Mat rect_to_raw_x, rect_to_raw_y;
  cv::initUndistortRectifyMap(K_raw, D, R, K_rect, cam.rect_size, CV_32FC1, rect_to_raw_x, rect_to_raw_y);
  double min_x, max_x, min_y, max_y;
  cv::minMaxLoc(rect_to_raw_x, &min_x, &max_x);
  cv::minMaxLoc(rect_to_raw_y, &min_y, &max_y);
  Require(min_x >= 0 && min_y >= 0 && max_x <= cam.raw_size.width - 1 && max_y <= cam.raw_size.height - 1,
          "raw drive: the distortion maps part of the rectified image outside the raw image; raise raw_margin");
  return warp;
}

cv::Mat Distort(const cv::Mat& rectified, const DistortionWarp& warp) {
  cv::Mat raw;
  cv::remap(rectified, raw, warp.map_x, warp.map_y, cv::INTER_LINEAR, cv::BORDER_REPLICATE);
  return raw;
}

// One synthetic Velodyne scan from the left depth map (see the header).
std::vector<VelodynePoint> SynthesiseScan(const cv::Mat& depth, const Eigen::Matrix3d& K,
                                          const Eigen::Isometry3d& rect_from_velo, const KittiRawDriveOptions& o) {
  const Eigen::Isometry3d velo_from_rect = rect_from_velo.inverse();
  const Eigen::Matrix3d K_inv = K.inverse();
  const int columns = static_cast<int>(std::lround(360.0 / o.velodyne_azimuth_step_deg));
  cv::Mat taken(depth.size(), CV_8U, cv::Scalar(0));
  std::vector<VelodynePoint> points;
  for (int beam = 0; beam < o.velodyne_beams; ++beam) {
    const double elevation =
        (kTopBeamElevationDeg + (kBottomBeamElevationDeg - kTopBeamElevationDeg) * beam / (o.velodyne_beams - 1)) *
        kDegToRad;
    for (int column = 0; column < columns; ++column) {
      const double azimuth = (-180.0 + column * o.velodyne_azimuth_step_deg) * kDegToRad;
      const Eigen::Vector3d ray(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
                                std::sin(elevation));
      const Eigen::Vector3d ray_camera = rect_from_velo.linear() * ray;
      bool in_view = false;
      if (ray_camera.z() > kMinViewCosine) {
        const Eigen::Vector3d pixel = K * ray_camera;
        const long u = std::lround(pixel.x() / pixel.z()), v = std::lround(pixel.y() / pixel.z());
        if (u >= 0 && v >= 0 && u < depth.cols && v < depth.rows) {
          in_view = true;
          const float z = depth.at<float>(static_cast<int>(v), static_cast<int>(u));
          uchar& seen = taken.at<uchar>(static_cast<int>(v), static_cast<int>(u));
          if (z > 0 && !seen) {
            const Eigen::Vector3d X = velo_from_rect * (z * (K_inv * Eigen::Vector3d(u, v, 1.0)));
            // The scanner's limit is on the range from the Velodyne, not on the camera depth.
            if (X.norm() < o.velodyne_max_range) {
              seen = 1;
              points.emplace_back(static_cast<float>(X.x()), static_cast<float>(X.y()), static_cast<float>(X.z()), 0.3f);
            }
          }
        }
      }
      if (!in_view && ray.z() < 0) {  // outside the camera's view: the ground plane around the car
        const double range = -o.velodyne_height / ray.z();
        const Eigen::Vector3d X = range * ray;
        // The Velodyne sits behind and above the camera, so a ray just outside the camera's view can
        // still hit ground the camera sees; the scene there is the simulator's, not a flat plane.
        const Eigen::Vector3d X_camera = rect_from_velo * X;
        const Eigen::Vector3d pixel = K * X_camera;
        const bool seen_by_camera = X_camera.z() > 0 && pixel.x() / pixel.z() > -1.0 &&
                                    pixel.y() / pixel.z() > -1.0 && pixel.x() / pixel.z() < depth.cols &&
                                    pixel.y() / pixel.z() < depth.rows;
        if (range < o.velodyne_max_range && !seen_by_camera) {
          points.emplace_back(static_cast<float>(X.x()), static_cast<float>(X.y()), static_cast<float>(X.z()), 0.1f);
        }
      }
    }
  }
  return points;
}

void WriteTextScan(const std::string& path, const std::vector<VelodynePoint>& points) {
  WriteText(path, [&](std::ostream& out) {
    out << std::setprecision(9);
    for (const VelodynePoint& p : points) out << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << p.w() << '\n';
  });
}

void WriteTimestamps(const std::string& path, const std::vector<double>& times) {
  WriteText(path, [&](std::ostream& out) {
    for (double t : times) out << FormatKittiRawTimestamp(t) << '\n';
  });
}

}  // namespace

KittiRawRig KittiRawRig::KittiLike() {
  KittiRawRig rig;
  rig.velo_from_imu = Rigid(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()).toRotationMatrix(), {-0.81, 0.32, -0.80});
  Eigen::Matrix3d axes;  // Velodyne x forward, y left, z up -> camera x right, y down, z forward
  axes << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  rig.cam0_from_velo =
      Rigid(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()).toRotationMatrix() * axes, {-0.004, -0.076, -0.27});
  rig.rect_from_cam0 = Eigen::AngleAxisd(0.005, Eigen::Vector3d(0.3, 1, 0.2).normalized()).toRotationMatrix();
  return rig;
}

Eigen::Isometry3d KittiRawRig::RectifiedFromVelodyne() const {
  return Rigid(rect_from_cam0, Eigen::Vector3d::Zero()) * cam0_from_velo;
}

Eigen::Isometry3d KittiRawRig::RectifiedFromImu() const { return RectifiedFromVelodyne() * velo_from_imu; }

void KittiRawDriveOptions::Check() const {
  Require(date.size() == 10 && date[4] == '_' && date[7] == '_', "raw drive: date '" + date + "' is not YYYY_MM_DD");
  Require(drive >= 0 && drive <= 9999, "raw drive: drive number must be 0..9999");
  Require(distortion.size() == 5, "raw drive: distortion needs 5 coefficients (k1 k2 p1 p2 k3)");
  Require(raw_margin >= 0.0 && raw_margin < 1.0, "raw drive: raw_margin must be in [0, 1)");
  Require(right_dropped.empty() || extract, "raw drive: only extract drives drop frames (sync drives are synchronised)");
  Require(right_trigger_offset >= 0.0 && right_trigger_offset < 0.005,
          "raw drive: right_trigger_offset must be in [0, 5 ms) (the reader pairs within 10 ms)");
  Require(oxts_packets_per_frame >= 1, "raw drive: oxts_packets_per_frame must be >= 1");
  Require(velodyne_beams >= 2 && velodyne_azimuth_step_deg > 0.0 && velodyne_max_range > 0.0 && velodyne_height > 0.0,
          "raw drive: Velodyne beams >= 2, azimuth step, range and height > 0");
  Require(std::abs(latitude) < 80.0 && std::abs(longitude) <= 180.0, "raw drive: latitude/longitude out of range");
}

namespace {

// Everything about a drive that is known before a frame is written: its folders, cameras and the texts
// of the date folder's calibration files.
struct DrivePlan {
  RawCamera left, right;
  KittiRawRig rig = KittiRawRig::KittiLike();
  std::string date_dir, drive_name, drive_dir, marker;
  std::vector<std::pair<std::string, std::string>> calibration;  // path, contents
};

DrivePlan PlanDrive(const std::string& raw_root, const KittiRawDriveOptions& options, const StereoCamera& camera) {
  DrivePlan plan;
  plan.left.K_rect << camera.left.fx, 0, camera.left.cx, 0, camera.left.fy, camera.left.cy, 0, 0, 1;
  plan.left.rect_size = cv::Size(camera.left.width, camera.left.height);
  const int margin_x = static_cast<int>(std::lround(options.raw_margin * camera.left.width));
  const int margin_y = static_cast<int>(std::lround(options.raw_margin * camera.left.height));
  plan.left.raw_size = options.extract ? cv::Size(camera.left.width + 2 * margin_x, camera.left.height + 2 * margin_y)
                                       : plan.left.rect_size;
  plan.left.K_raw = plan.left.K_rect;
  if (options.extract) plan.left.K_raw(0, 2) += margin_x, plan.left.K_raw(1, 2) += margin_y;
  plan.right = plan.left;
  plan.right.tx = -camera.left.fx * camera.baseline;

  const char* flavour = options.extract ? "extract" : "sync";
  char drive_name[64];
  std::snprintf(drive_name, sizeof(drive_name), "%s_drive_%04d_%s", options.date.c_str(), options.drive, flavour);
  plan.drive_name = drive_name;
  plan.date_dir = JoinPath(raw_root, options.date);
  plan.drive_dir = JoinPath(plan.date_dir, plan.drive_name);
  plan.marker = JoinPath(plan.drive_dir, kSimulatedDriveMarker);
  const KittiRawRig& rig = plan.rig;
  plan.calibration = {
      {JoinPath(plan.date_dir, "calib_imu_to_velo.txt"), TextOf([&](std::ostream& out) { WriteRigid(out, rig.velo_from_imu); })},
      {JoinPath(plan.date_dir, "calib_velo_to_cam.txt"), TextOf([&](std::ostream& out) { WriteRigid(out, rig.cam0_from_velo); })},
      {JoinPath(plan.date_dir, "calib_cam_to_cam.txt"),
       CamToCamText(plan.left, plan.right, rig, options.distortion, camera.baseline)}};
  return plan;
}

// Throws when the drive may not be written (see WriteKittiRawDrive's header comment); writes nothing.
void CheckDrivePlan(const DrivePlan& plan, const KittiRawDriveOptions& options) {
  namespace fs = std::filesystem;
  const bool drive_is_simulated = fs::exists(plan.marker);
  RequireCalibrationReplaceable(plan.date_dir, plan.drive_name, drive_is_simulated, plan.calibration);
  if (fs::is_directory(plan.drive_dir) && !fs::is_empty(plan.drive_dir)) {
    RequireFile(drive_is_simulated, plan.drive_dir,
                "exists and was not written by `dvso simulate` (no " + std::string(kSimulatedDriveMarker) +
                    "); not overwritten: choose another --raw-out");
  }
  if (options.extract) {  // throws when raw_margin leaves part of a rectified image outside the raw one
    MakeDistortionWarp(plan.left, plan.rig, options.distortion);
    MakeDistortionWarp(plan.right, plan.rig, options.distortion);
  }
}

}  // namespace

void CheckKittiRawDriveWritable(const std::string& raw_root, const KittiRawDriveOptions& options,
                                const StereoCamera& camera) {
  options.Check();
  CheckDrivePlan(PlanDrive(raw_root, options, camera), options);
}

KittiRawDriveSummary WriteKittiRawDrive(const std::string& sequence_dir, const std::string& raw_root,
                                        const KittiRawDriveOptions& options, bool show_progress) {
  options.Check();
  const std::unique_ptr<SequenceReader> sequence = OpenKittiSequence(sequence_dir);
  RequireFile(sequence->is_stereo(), sequence_dir,
              "a raw drive needs the stereo pair image_0/ image_1/: " + sequence->NotStereoReason());
  const std::string depth_dir = JoinPath(sequence_dir, "depth_0");
  RequireFile(fs::is_directory(depth_dir), depth_dir, "no simulated depth (write the sequence with `dvso simulate`)");
  const Trajectory poses = ReadTrajectory(JoinPath(sequence_dir, "poses.txt"), TrajectoryFormat::kKitti);
  RequireFile(static_cast<int>(poses.size()) == sequence->size(), JoinPath(sequence_dir, "poses.txt"),
              std::to_string(poses.size()) + " poses for " + std::to_string(sequence->size()) + " frames");

  const DrivePlan plan = PlanDrive(raw_root, options, sequence->camera());
  CheckDrivePlan(plan, options);
  const RawCamera& left = plan.left;
  const RawCamera& right = plan.right;
  const KittiRawRig& rig = plan.rig;
  const auto& calibration = plan.calibration;
  KittiRawDriveSummary summary;
  summary.drive_dir = plan.drive_dir;
  summary.color = sequence->has_color();
  const int cameras = summary.color ? 4 : 2;
  namespace fs = std::filesystem;
  const std::string& marker = plan.marker;
  if (fs::is_directory(summary.drive_dir) && !fs::is_empty(summary.drive_dir)) {
    // An earlier simulation's drive (CheckDrivePlan found its marker): remove its frames and timestamps
    // (a shorter or grey rerun would otherwise leave frames a reader takes for this drive's, and a run
    // stopped halfway must still look incomplete: timestamps are written last).
    // Temporary files of a writer killed between writing and renaming (0000000001.tmp-writing.png,
    // timestamps.tmp-writing.txt) go too: RemoveFrameFiles does not match them, and they would keep
    // the emptied folders in place.
    RemoveUnfinishedAtomicWrites(summary.drive_dir);
    for (const char* sensor : {"image_00", "image_01", "image_02", "image_03", "velodyne_points", "oxts"}) {
      const std::string sensor_dir = JoinPath(summary.drive_dir, sensor);
      RemoveUnfinishedAtomicWrites(JoinPath(sensor_dir, "data"));
      RemoveUnfinishedAtomicWrites(sensor_dir);
      RemoveFrameFiles(JoinPath(sensor_dir, "data"));
      std::error_code ignored;  // folders that hold other files stay (remove() only takes empty ones)
      fs::remove(JoinPath(sensor_dir, "timestamps.txt"), ignored);
      fs::remove(JoinPath(sensor_dir, "data"), ignored);
      fs::remove(sensor_dir, ignored);
    }
  }
  EnsureDirectory(summary.drive_dir);
  WriteText(marker, [&](std::ostream& out) {
    out << "Simulated KITTI raw drive written by `dvso simulate --raw-layout`; a rerun into this folder replaces it.\n";
  });
  for (int id = 0; id < cameras; ++id) EnsureDirectory(JoinPath(summary.drive_dir, "image_0" + std::to_string(id) + "/data"));
  EnsureDirectory(JoinPath(summary.drive_dir, "velodyne_points/data"));
  EnsureDirectory(JoinPath(summary.drive_dir, "oxts/data"));

  DistortionWarp left_warp, right_warp;
  if (options.extract) {
    left_warp = MakeDistortionWarp(left, rig, options.distortion);
    right_warp = MakeDistortionWarp(right, rig, options.distortion);
  }
  const std::set<int> dropped(options.right_dropped.begin(), options.right_dropped.end());
  const Eigen::Isometry3d rect_from_velo = rig.RectifiedFromVelodyne();
  const Eigen::Isometry3d rect_from_imu = rig.RectifiedFromImu();
  const double scale = MercatorScale(options.latitude);
  OxtsPacket origin;
  origin.lat = options.latitude, origin.lon = options.longitude, origin.alt = options.altitude;
  origin.yaw = options.heading;
  const Eigen::Isometry3d world_from_first_imu = OxtsToPose(origin, scale);

  std::vector<double> left_times, right_times, oxts_times;
  int right_written = 0;
  std::unique_ptr<ProgressBar> bar;
  if (show_progress) bar = std::make_unique<ProgressBar>("raw drive", sequence->size());
  SequenceReadOptions read;
  read.load_color = summary.color;
  for (int i = 0; i < sequence->size(); ++i) {
    const StereoFrame frame = sequence->Read(i, read);
    const double time = options.start_time + sequence->timestamps()[i] - sequence->timestamps()[0];
    const std::string name = RawName(i, ".png");
    auto image_path = [&](int id, const std::string& file) {
      return JoinPath(JoinPath(summary.drive_dir, "image_0" + std::to_string(id) + "/data"), file);
    };
    WritePng(image_path(0, name), options.extract ? Distort(frame.left, left_warp) : frame.left);
    if (summary.color) WritePng(image_path(2, name), options.extract ? Distort(frame.left_color, left_warp) : frame.left_color);
    left_times.push_back(time);
    if (!dropped.count(i)) {
      // Extract drives number every camera's files on their own, so a drop shifts the right names.
      const std::string right_name = RawName(options.extract ? right_written : i, ".png");
      WritePng(image_path(1, right_name), options.extract ? Distort(frame.right, right_warp) : frame.right);
      if (summary.color) {
        WritePng(image_path(3, right_name), options.extract ? Distort(frame.right_color, right_warp) : frame.right_color);
      }
      right_times.push_back(time + (options.extract ? options.right_trigger_offset : 0.0));
      ++right_written;
    }

    const cv::Mat depth = ReadKittiMapPng(JoinPath(depth_dir, sequence->FrameName(i) + ".png"));
    RequireFile(depth.size() == left.rect_size, JoinPath(depth_dir, sequence->FrameName(i) + ".png"),
                "depth map size differs from the images");
    const std::vector<VelodynePoint> scan = SynthesiseScan(depth, left.K_rect, rect_from_velo, options);
    summary.velodyne_points += static_cast<long>(scan.size());
    const std::string scan_path = JoinPath(JoinPath(summary.drive_dir, "velodyne_points/data"),
                                           RawName(i, options.extract ? ".txt" : ".bin"));
    if (options.extract) {
      WriteTextScan(scan_path, scan);
    } else {
      WriteVelodyneScan(scan_path, scan);
    }

    // IMU pose in the Mercator world: first IMU pose * (IMU motion = camera motion seen from the IMU).
    // Extract drives: several packets per frame, the first at the frame's time, the others on the way to
    // the next frame (translation linear, rotation slerp); the last frame has its own packet only.
    const bool last = i + 1 == sequence->size();
    const int per_frame = options.extract && !last ? options.oxts_packets_per_frame : 1;
    const Eigen::Isometry3d& a = poses.poses[i].T_world_camera;
    const Eigen::Isometry3d& b = poses.poses[last ? i : i + 1].T_world_camera;
    const double next_time = last ? time : options.start_time + sequence->timestamps()[i + 1] - sequence->timestamps()[0];
    for (int k = 0; k < per_frame; ++k) {
      const double s = static_cast<double>(k) / per_frame;
      Eigen::Isometry3d first_camera_from_camera = Eigen::Isometry3d::Identity();
      first_camera_from_camera.linear() =
          Eigen::Quaterniond(a.linear()).slerp(s, Eigen::Quaterniond(b.linear())).toRotationMatrix();
      first_camera_from_camera.translation() = (1.0 - s) * a.translation() + s * b.translation();
      const Eigen::Isometry3d world_from_imu =
          world_from_first_imu * rect_from_imu.inverse() * first_camera_from_camera * rect_from_imu;
      WriteOxtsPacket(JoinPath(JoinPath(summary.drive_dir, "oxts/data"), RawName(static_cast<int>(oxts_times.size()), ".txt")),
                      PoseToOxts(world_from_imu, scale));
      oxts_times.push_back(time + s * (next_time - time));
    }
    if (bar) bar->Update(i + 1);
  }
  if (bar) bar->Finish();
  summary.frames = sequence->size();
  summary.right_dropped = sequence->size() - right_written;

  // Timestamps and calibration last: a drive without them is recognisably incomplete.
  for (int id = 0; id < cameras; ++id) {
    WriteTimestamps(JoinPath(summary.drive_dir, "image_0" + std::to_string(id) + "/timestamps.txt"),
                    id % 2 == 0 ? left_times : right_times);
  }
  WriteTimestamps(JoinPath(summary.drive_dir, "velodyne_points/timestamps.txt"), left_times);
  WriteTimestamps(JoinPath(summary.drive_dir, "oxts/timestamps.txt"), oxts_times);
  for (const auto& [path, text] : calibration) WriteText(path, text);
  return summary;
}

}  // namespace dvso
