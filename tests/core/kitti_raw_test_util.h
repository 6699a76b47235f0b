// A KITTI raw date folder's calibration files with KITTI-like values (the rig of
// core/kitti_raw_writer.h), written for tests of the raw readers (OXTS poses, Velodyne depth).
#pragma once

#include <Eigen/Geometry>
#include <filesystem>
#include <fstream>

#include "core/kitti_raw_writer.h"

namespace dvso::testing {

inline Eigen::Isometry3d Rigid(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

inline void WriteRigidCalibration(const std::filesystem::path& path, const Eigen::Isometry3d& T) {
  std::ofstream out(path);
  out.precision(17);
  out << "calib_time: 25-May-2012 16:47:16\nR:";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out << ' ' << T.linear()(r, c);
  out << "\nT: " << T.translation().x() << ' ' << T.translation().y() << ' ' << T.translation().z() << '\n';
}

struct RawCalibration {
  Eigen::Isometry3d velo_from_imu, cam0_from_velo;
  Eigen::Matrix3d rect;                 // R_rect_00
  Eigen::Matrix<double, 3, 4> P_rect_02;
  double fx = 721.5377;
  // t = K^-1 P_rect_02[:, 3] by hand: t.z = P(2,3), t.x = (P(0,3) - cx t.z) / fx, t.y = (P(1,3) - cy t.z) / fy.
  Eigen::Vector3d camera2_offset{(44.85728 - 609.5593 * 0.002745884) / 721.5377,
                                 (0.2163791 - 172.854 * 0.002745884) / 721.5377, 0.002745884};
};

// Writes calib_imu_to_velo.txt, calib_velo_to_cam.txt and calib_cam_to_cam.txt (1242x375 rectified).
inline RawCalibration WriteRawCalibration(const std::filesystem::path& dir) {
  RawCalibration c;
  const KittiRawRig rig = KittiRawRig::KittiLike();  // the simulator's raw drives use the same rig
  c.velo_from_imu = rig.velo_from_imu;
  c.cam0_from_velo = rig.cam0_from_velo;
  c.rect = rig.rect_from_cam0;
  c.P_rect_02 << c.fx, 0, 609.5593, 44.85728, 0, c.fx, 172.854, 0.2163791, 0, 0, 1, 0.002745884;
  WriteRigidCalibration(dir / "calib_imu_to_velo.txt", c.velo_from_imu);
  WriteRigidCalibration(dir / "calib_velo_to_cam.txt", c.cam0_from_velo);
  std::ofstream out(dir / "calib_cam_to_cam.txt");
  out.precision(17);
  out << "calib_time: 09-Jan-2012 13:57:47\ncorner_dist: 9.950000e-02\nR_rect_00:";
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 3; ++col) out << ' ' << c.rect(r, col);
  out << "\nS_rect_00: 1.242000e+03 3.750000e+02\nP_rect_00: " << c.fx << " 0 609.5593 0 0 " << c.fx
      << " 172.854 0 0 0 1 0\nS_rect_02: 1.242000e+03 3.750000e+02\nP_rect_02:";
  for (int r = 0; r < 3; ++r)
    for (int col = 0; col < 4; ++col) out << ' ' << c.P_rect_02(r, col);
  out << '\n';
  return c;
}

}  // namespace dvso::testing
