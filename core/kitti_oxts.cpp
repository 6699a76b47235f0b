#include "core/kitti_oxts.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_raw_calibration.h"
#include "core/sequence_common.h"

namespace dvso {

namespace fs = std::filesystem;

namespace {

constexpr int kOxtsValues = 30;  // values per packet in the devkit's layout
constexpr double kDegToRad = M_PI / 180.0;

}  // namespace

OxtsPacket ReadOxtsPacket(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open OXTS packet");
  std::vector<double> v;
  double x = 0.0;
  while (in >> x) v.push_back(x);
  RequireFile(in.eof() && v.size() >= 6, path, "an OXTS packet needs >= 6 numbers (lat lon alt roll pitch yaw ...)");
  OxtsPacket p;
  p.lat = v[0], p.lon = v[1], p.alt = v[2], p.roll = v[3], p.pitch = v[4], p.yaw = v[5];
  return p;
}

void WriteOxtsPacket(const std::string& path, const OxtsPacket& packet) {
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out << std::setprecision(17) << packet.lat << ' ' << packet.lon << ' ' << packet.alt << ' ' << packet.roll << ' '
        << packet.pitch << ' ' << packet.yaw;
    for (int i = 6; i < kOxtsValues; ++i) out << " 0";
    out << '\n';
  });
}

double MercatorScale(double lat_deg) { return std::cos(lat_deg * kDegToRad); }

Eigen::Isometry3d OxtsToPose(const OxtsPacket& p, double scale) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() << scale * p.lon * M_PI * kEarthRadius / 180.0,
      scale * kEarthRadius * std::log(std::tan((90.0 + p.lat) * M_PI / 360.0)), p.alt;
  T.linear() = (Eigen::AngleAxisd(p.yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(p.pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(p.roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  return T;
}

OxtsPacket PoseToOxts(const Eigen::Isometry3d& T, double scale) {
  OxtsPacket p;
  const Eigen::Vector3d t = T.translation();
  p.lon = t.x() * 180.0 / (scale * M_PI * kEarthRadius);
  p.lat = std::atan(std::exp(t.y() / (scale * kEarthRadius))) * 360.0 / M_PI - 90.0;
  p.alt = t.z();
  // R = Rz(yaw) Ry(pitch) Rx(roll): R(2,0) = -sin(pitch), R(2,1) / R(2,2) = tan(roll), R(1,0) / R(0,0) = tan(yaw).
  const Eigen::Matrix3d R = T.linear();
  p.pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  p.roll = std::atan2(R(2, 1), R(2, 2));
  p.yaw = std::atan2(R(1, 0), R(0, 0));
  return p;
}

Eigen::Isometry3d CameraFromImu(const std::string& calib_dir, int camera) {
  const RawCameraCalibration calibration(calib_dir);
  // P_rect_0X = K [I | t]: rectified camera X = rectified camera 00 moved by t (internal::RectifiedCameraOffset).
  const Eigen::Matrix<double, 3, 4> P = calibration.Projection(camera);
  std::vector<double> projection;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 4; ++col) projection.push_back(P(row, col));
  }
  const cv::Vec3d offset = internal::RectifiedCameraOffset(projection, calibration.path);
  Eigen::Isometry3d shift = Eigen::Isometry3d::Identity();
  shift.translation() = Eigen::Vector3d(offset[0], offset[1], offset[2]);
  const Eigen::Isometry3d velo_from_imu = ReadRigidCalibration(JoinPath(calib_dir, "calib_imu_to_velo.txt"));
  return shift * calibration.RectifiedFromVelodyne() * velo_from_imu;
}

std::string OxtsPacketPath(const std::string& drive_dir, long long number) {
  char name[32];
  std::snprintf(name, sizeof(name), "%010lld.txt", number);
  return (fs::path(drive_dir) / "oxts" / "data" / name).string();
}

std::map<long long, Eigen::Isometry3d> OxtsCameraPoses(const std::string& drive_dir, int camera) {
  const fs::path data_dir = fs::path(drive_dir) / "oxts" / "data";
  RequireFile(fs::is_directory(data_dir), data_dir.string(), "no OXTS folder (KITTI raw layout: DRIVE/oxts/data/)");
  std::map<long long, std::string> files;  // by file number
  for (const auto& entry : fs::directory_iterator(data_dir)) {
    if (!entry.is_regular_file() || entry.path().extension() != ".txt") continue;
    const std::optional<long long> number = ParseFrameNumber(entry.path().stem().string());
    RequireFile(number.has_value(), entry.path().string(),
                "an OXTS packet is named by its frame number (oxts/data/NNNNNNNNNN.txt)");
    const auto [it, inserted] = files.emplace(*number, entry.path().string());
    RequireFile(inserted, entry.path().string(), "has the frame number of " + it->second + " too");
  }
  RequireFile(!files.empty(), data_dir.string(), "no OXTS packets (*.txt)");
  // Every calibration file sits in the same folder (the date folder, or copied into the drive).
  const std::string calib_dir = FindRawCalibrationDir(drive_dir);
  const Eigen::Isometry3d imu_from_camera = CameraFromImu(calib_dir, camera).inverse();
  std::map<long long, Eigen::Isometry3d> poses;
  double scale = 0.0;
  Eigen::Isometry3d first_inverse = Eigen::Isometry3d::Identity();
  for (const auto& [number, path] : files) {
    const OxtsPacket packet = ReadOxtsPacket(path);
    const bool first = poses.empty();
    if (first) scale = MercatorScale(packet.lat);
    const Eigen::Isometry3d T_world_camera = OxtsToPose(packet, scale) * imu_from_camera;
    if (first) first_inverse = T_world_camera.inverse();
    poses.emplace(number, first_inverse * T_world_camera);
  }
  return poses;
}

size_t NearestTimestamp(const std::vector<double>& times, double t) {
  Require(!times.empty(), "no timestamps to pair with");
  size_t best = 0;
  for (size_t k = 1; k < times.size(); ++k) {
    if (std::abs(times[k] - t) < std::abs(times[best] - t)) best = k;
  }
  return best;
}

}  // namespace dvso
