// Calibration files of a KITTI raw date folder (raw data devkit readme):
// calib_cam_to_cam.txt (K_xx, D_xx, R_xx, T_xx, S_rect_xx, R_rect_xx, P_rect_xx),
// calib_velo_to_cam.txt and calib_imu_to_velo.txt ("R:" 9 values, "T:" 3 values).
// Every file is "KEY: numbers" lines (calib_time has text and is skipped).
#pragma once

#include <Eigen/Geometry>
#include <map>
#include <string>
#include <vector>

namespace dvso {

using KittiCalibration = std::map<std::string, std::vector<double>>;

// Reads every numeric "KEY: v1 v2 ..." line. Throws naming the file if it cannot be opened.
KittiCalibration ReadKittiCalibration(const std::string& path);
// The entry `key` with exactly `count` numbers; throws naming `path` and the key otherwise.
const std::vector<double>& CalibrationEntry(const KittiCalibration& calibration, const std::string& key, size_t count,
                                            const std::string& path);
// Row-major 3x3 from 9 numbers.
Eigen::Matrix3d RowMajor3x3(const std::vector<double>& values);

// "R:" + "T:" rigid calibration (calib_imu_to_velo.txt, calib_velo_to_cam.txt): T_to_from, which
// maps points of the "from" sensor into the "to" sensor. Throws if R is not a rotation.
Eigen::Isometry3d ReadRigidCalibration(const std::string& path);

// calib_cam_to_cam.txt of a calibration folder, read once, and what every rectified camera shares.
struct RawCameraCalibration {
  explicit RawCameraCalibration(const std::string& calib_dir);
  // P_rect_0X of rectified camera `camera` (0..3) = K [I | t] in rectified camera 00; throws naming the
  // file for a camera outside 0..3, a missing entry or a non-positive focal length.
  Eigen::Matrix<double, 3, 4> Projection(int camera) const;
  // R_rect_00 * T_cam0_velo (calib_velo_to_cam.txt): Velodyne points into rectified camera 00, the frame
  // every P_rect_0X projects from.
  Eigen::Isometry3d RectifiedFromVelodyne() const;

  std::string dir;           // the calibration folder
  std::string path;          // its calib_cam_to_cam.txt
  KittiCalibration entries;  // that file's entries
};

// The folder holding a drive's calibration files: the drive folder itself when they were copied
// there, else its parent (the date folder of the raw layout). Throws naming the drive otherwise.
std::string FindRawCalibrationDir(const std::string& drive_dir);

}  // namespace dvso
