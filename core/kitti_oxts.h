// Ground-truth poses of a KITTI raw drive from its GPS/IMU (OXTS) packets, in
// the KITTI raw devkit's convention (readme of the raw data development kit,
// convertOxtsToPose / latToScale / latlonToMercator):
//   scale = cos(lat_0 * pi / 180)                       (Mercator scale of the FIRST packet)
//   t     = ( scale * lon * pi * r_earth / 180,
//             scale * r_earth * ln(tan((90 + lat) * pi / 360)),
//             alt ),                                    r_earth = 6378137 m
//   R     = Rz(yaw) * Ry(pitch) * Rx(roll)              (IMU frame: x forward, y left, z up)
// gives T_world_imu(i); the poses are moved into a rectified camera through the
// drive's calibration,
//   T_camrect_imu = S_x * R_rect_00 * T_cam0_velo * T_velo_imu,
// (S_x: the rectified camera's offset along x from P_rect_0X, identity for camera 00),
//   T_world_cam(i) = T_world_imu(i) * T_camrect_imu^-1,
// and expressed relative to the first frame's camera: T_cam(0)^-1 * T_cam(i),
// the KITTI odometry poses' convention. GPS/IMU poses are approximate (the
// devkit quotes a few cm to dm of position error and drift in GPS-denied areas):
// fine for evaluating odometry over hundreds of metres, not for sub-cm checks.
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

namespace dvso {

// The pose part of one OXTS packet (the first 6 of its 30 values).
struct OxtsPacket {
  double lat = 0.0, lon = 0.0;            // degrees
  double alt = 0.0;                       // m
  double roll = 0.0, pitch = 0.0, yaw = 0.0;  // rad
};

constexpr double kEarthRadius = 6378137.0;  // m, the devkit's (WGS-84 equatorial) radius

// Reads `oxts/data/NNNNNNNNNN.txt` (one line, >= 6 numbers; the devkit's 30). Throws naming the file.
OxtsPacket ReadOxtsPacket(const std::string& path);
// Writes a packet in the devkit's 30-value layout (velocities etc. zero); for synthetic drives and tests.
void WriteOxtsPacket(const std::string& path, const OxtsPacket& packet);

// Mercator scale of the first packet's latitude.
double MercatorScale(double lat_deg);
// The devkit's pose of the IMU in the Mercator world frame.
Eigen::Isometry3d OxtsToPose(const OxtsPacket& packet, double scale);
// Inverse of OxtsToPose (R = Rz(yaw) Ry(pitch) Rx(roll), |pitch| < pi/2).
OxtsPacket PoseToOxts(const Eigen::Isometry3d& T_world_imu, double scale);

// T_camrect_imu of rectified camera `camera` (0..3) of a raw date folder's calibration files.
Eigen::Isometry3d CameraFromImu(const std::string& calib_dir, int camera);

// Camera poses of a drive, one per packet `drive/oxts/data/NNNNNNNNNN.txt`, keyed by the packet's file
// number (not its position in the listing: a missing file must not shift the packets after it onto other
// frames), relative to the lowest-numbered packet (KITTI odometry convention). The calibration files are
// looked up in the drive folder, then in its parent (the date folder of the raw layout). Throws naming
// the file for a packet whose name is not a frame number.
std::map<long long, Eigen::Isometry3d> OxtsCameraPoses(const std::string& drive_dir, int camera);
// The path of packet `number` of a drive (oxts/data/%010d.txt), for messages about a missing one.
std::string OxtsPacketPath(const std::string& drive_dir, long long number);

// Extract drives: a frame whose nearest OXTS packet (100 Hz, so normally <= 5 ms away) is farther than this,
// half a 10 Hz camera period, gets a warning (real recordings have gaps in the GPS/IMU stream).
constexpr double kMaxOxtsFrameGap = 0.05;  // s
// Index of the time in `times` nearest to `t` (ties: the first); `times` need not be sorted (the OXTS
// timestamps of real drives jump). Throws dvso::Error when `times` is empty.
size_t NearestTimestamp(const std::vector<double>& times, double t);

}  // namespace dvso
