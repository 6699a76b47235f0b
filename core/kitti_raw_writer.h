// Synthetic KITTI raw drives: rewrites a sequence simulated by `dvso simulate`
// (KITTI odometry layout with depth_0/ and poses.txt) in the layout of the KITTI
// raw data devkit, so that every raw reader (sequence_kitti_raw.cpp,
// kitti_velodyne.h, kitti_oxts.h) is exercised on data whose truth is known:
//
//   ROOT/DATE/calib_cam_to_cam.txt  K_0X D_0X R_0X T_0X S_0X, S_rect_0X R_rect_0X P_rect_0X (X = 0..3)
//   ROOT/DATE/calib_velo_to_cam.txt calib_imu_to_velo.txt      (the rig below)
//   ROOT/DATE/DATE_drive_NNNN_sync|extract/
//     image_0X/data/%010d.png + image_0X/timestamps.txt        (00/01 grey, 02/03 colour if simulated)
//     velodyne_points/data/%010d.bin (sync) | .txt (extract) + timestamps.txt
//     oxts/data/%010d.txt + oxts/timestamps.txt                (one packet per frame)
//
// The simulated camera is rectified camera 00; the colour cameras 02/03 sit at
// the grey cameras' centres (the simulator renders colour there), so P_rect_02 =
// P_rect_00 and P_rect_03 = P_rect_01. Every unrectified camera shares the
// orientation R_rect_00^T of the rectified pair.
//  - sync: the rectified images as they are; all cameras keep every frame.
//  - extract: each image is warped into its unrectified, distorted camera
//    (raw pixel -> undistort with K_0X, D_0X -> rotate by R_rect_0X -> P_rect_0X,
//    the inverse of what the reader's rectification does), on a raw image larger
//    than the rectified one; the right cameras drop the frames asked for and are
//    triggered `right_trigger_offset` later, every camera numbering its own files.
//  - Velodyne: rays of a 64-beam scanner (HDL-64E elevations) are cast from the
//    Velodyne centre; a ray inside the left camera's view takes the simulator's
//    depth at the pixel its direction projects to, and the point is placed on
//    that pixel's viewing ray at that depth, so `gt-depth` must give back the
//    simulated depth at exactly those pixels; rays outside the view hit a flat
//    ground (points behind the car, which gt-depth must drop).
//  - OXTS: the poses of poses.txt moved into the IMU through the rig and
//    written as lat/lon/alt/roll/pitch/yaw with the devkit's Mercator projection
//    (kitti_oxts.h), starting at `latitude`, `longitude`, `altitude`, `heading`.
#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/camera.h"

namespace dvso {

// The sensor rig of a synthetic drive: KITTI-like mounting (IMU behind and below the Velodyne,
// cameras in front of and below it) with small rotations so that no transform is the identity.
struct KittiRawRig {
  Eigen::Isometry3d velo_from_imu;   // calib_imu_to_velo.txt
  Eigen::Isometry3d cam0_from_velo;  // calib_velo_to_cam.txt (unrectified camera 00)
  Eigen::Matrix3d rect_from_cam0;    // R_rect_00 (= R_rect_0X of every camera)

  static KittiRawRig KittiLike();
  // R_rect_00 * T_cam0_velo: Velodyne points into rectified camera 00 (the simulated camera).
  Eigen::Isometry3d RectifiedFromVelodyne() const;
  // R_rect_00 * T_cam0_velo * T_velo_imu.
  Eigen::Isometry3d RectifiedFromImu() const;
};

struct KittiRawDriveOptions {
  bool extract = false;              // unrectified, distorted "_extract" drive; else a rectified "_sync" drive
  std::string date = "2011_09_26";   // date folder and drive name prefix (YYYY_MM_DD)
  int drive = 1;                     // drive number (DATE_drive_%04d_FLAVOUR)
  std::vector<double> distortion = {-0.12, 0.05, 4e-4, -3e-4, -0.01};  // D_0X (k1 k2 p1 p2 k3), extract only
  double raw_margin = 0.08;          // extract: raw images are larger than the rectified by this fraction per side
  std::vector<int> right_dropped;    // extract: frame indices the right cameras (01, 03) lose
  double right_trigger_offset = 4e-4;  // extract: s the right cameras' timestamps lag the left ones (< 10 ms)
  int oxts_packets_per_frame = 10;   // extract: GPS/IMU packets per camera frame (KITTI records it at 100 Hz,
                                     // cameras at 10 Hz; poses interpolated between frames); sync drives: 1
  double start_time = 1317042130.0;  // epoch seconds (UTC) of the first frame: 2011-09-26 13:02:10
  int velodyne_beams = 64;           // HDL-64E: elevations +2.0 .. -24.9 deg
  double velodyne_azimuth_step_deg = 0.2;  // azimuth resolution of the synthetic scan
  double velodyne_max_range = 120.0;       // m, points farther away (and sky) are not returned
  double velodyne_height = 1.73;     // m above the ground plane that rays outside the camera view hit
  double latitude = 49.011;          // first IMU packet, degrees (Karlsruhe)
  double longitude = 8.4237;         // degrees
  double altitude = 112.0;           // m
  double heading = 0.5;              // yaw of the first IMU pose (rad, east = 0)

  // Throws dvso::Error on invalid values.
  void Check() const;
};

// File in a drive folder written by WriteKittiRawDrive: only such a folder is ever overwritten.
inline constexpr const char* kSimulatedDriveMarker = "dvso_simulated_drive.txt";

struct KittiRawDriveSummary {
  std::string drive_dir;        // ROOT/DATE/DATE_drive_NNNN_FLAVOUR
  int frames = 0;               // frames of the left camera
  int right_dropped = 0;        // frames the right cameras lost
  long velodyne_points = 0;     // points written, all scans
  bool color = false;           // colour cameras 02/03 written
};

// Writes the drive of the simulated sequence `sequence_dir` under `raw_root` (created if needed).
// A drive folder of an earlier simulation (marked by kSimulatedDriveMarker) is replaced: its frame
// files and timestamps are removed first, so a shorter or grey rerun leaves nothing of it behind.
// Throws dvso::Error naming the file when the sequence lacks depth_0/, poses.txt or images, when
// the distortion would leave part of a rectified image outside its raw image, or when the drive
// folder exists without the marker (e.g. a real KITTI drive of the same name: never touched), or
// when a calibration file of the date folder exists with other contents and any other drive of the
// date (real or simulated) reads it: a drive's calibration is never changed under it.
KittiRawDriveSummary WriteKittiRawDrive(const std::string& sequence_dir, const std::string& raw_root,
                                        const KittiRawDriveOptions& options, bool show_progress = false);

// The checks of WriteKittiRawDrive that need no frame (options, drive folder, date folder's calibration,
// distortion margin) for a sequence whose calib.txt will read back as `camera`
// (KittiCalibrationAsReadBack): `dvso simulate` runs them before rendering. Writes nothing.
void CheckKittiRawDriveWritable(const std::string& raw_root, const KittiRawDriveOptions& options,
                                const StereoCamera& camera);

}  // namespace dvso
