// KITTI raw Velodyne scans and their projection into a rectified camera: the
// sparse depth ground truth of the Eigen split (paper section 5.1, Table 1), as
// monodepth's generate_depth_map builds it:
//   x_image ~ P_rect_0X * R_rect_00 * T_cam0_velo * X_velo     (homogeneous)
// points behind the Velodyne (x_velo < kMinForward) are dropped, a pixel hit by
// several points keeps the nearest. The value stored is, by default, the point's
// Velodyne forward distance x_velo, as the Eigen-split GT of monodepth and
// monodepth2 (generate_depth_map(..., vel_depth=True)); the camera depth z (the
// third homogeneous coordinate) is the other choice. On KITTI the Velodyne sits
// ~0.27 m behind camera 00, so z ~= x_velo - 0.27 m: published abs-rel numbers
// are measured against x_velo.
// Pixel convention: 0-based, pixel (u, v) covers [u - 0.5, u + 0.5), i.e. the
// projected coordinate is rounded (the convention of P_rect and of our
// simulator); monodepth additionally subtracts 1 (a MATLAB 1-based leftover),
// which moves its GT by one pixel left and up.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace dvso {

// x y z reflectance, as stored in velodyne_points/data/NNNNNNNNNN.bin (float32).
using VelodynePoint = Eigen::Vector4f;

// Reads a scan: .bin (float32 quadruples; the sync drives) or .txt (one "x y z reflectance" line per
// point; the extract drives). Throws naming the file if it is missing or malformed (a .bin whose
// size is not a multiple of 16 bytes, a text line without 4 numbers).
std::vector<VelodynePoint> ReadVelodyneScan(const std::string& path);
// Writes a .bin scan (for synthetic drives and tests).
void WriteVelodyneScan(const std::string& path, const std::vector<VelodynePoint>& points);

struct VelodyneProjection {
  Eigen::Matrix<double, 3, 4> velo_to_image;  // P_rect_0X * R_rect_00 * T_cam0_velo
  int width = 0, height = 0;                  // S_rect_0X: the rectified image size
};

// The projection into rectified camera `camera` (0..3) from a raw date folder's calibration.
VelodyneProjection ReadVelodyneProjection(const std::string& calib_dir, int camera);

// What a GT pixel holds: the point's Velodyne x (monodepth's vel_depth=True, the published Eigen-split
// protocol) or its depth along the rectified camera's optical axis.
enum class VelodyneDepthValue { kVelodyneX, kCameraZ };
// "velodyne-x" | "camera-z"; throws dvso::Error otherwise.
VelodyneDepthValue ParseVelodyneDepthValue(const std::string& name);

// CV_32F depth map (m) of the projection's size; 0 = no point. A pixel hit by several points keeps the
// smallest value of the chosen kind (monodepth keeps the minimum of the stored value too).
cv::Mat ProjectVelodyneDepth(const std::vector<VelodynePoint>& points, const VelodyneProjection& projection,
                             VelodyneDepthValue value = VelodyneDepthValue::kVelodyneX);

}  // namespace dvso
