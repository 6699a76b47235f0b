// Rectified pinhole cameras. Every module sees images through these: the
// simulator renders with them, the readers parse calibration into them, the
// odometry projects with them and the network resizes them.
#pragma once

#include <Eigen/Core>
#include <string>

namespace dvso {

struct PinholeCamera {
  double fx = 718.856;   // focal length in x, pixels (KITTI 00-02 default)
  double fy = 718.856;   // focal length in y, pixels
  double cx = 607.1928;  // principal point x, pixels
  double cy = 185.2157;  // principal point y, pixels
  int width = 1241;      // image width, pixels
  int height = 376;      // image height, pixels

  // Throws dvso::Error when a value is non-finite or out of range.
  void Check() const;

  Eigen::Vector2d Project(const Eigen::Vector3d& p_cam) const {
    return {fx * p_cam.x() / p_cam.z() + cx, fy * p_cam.y() / p_cam.z() + cy};
  }
  // Back-projects pixel (u, v) to the ray with z = 1.
  Eigen::Vector3d Unproject(double u, double v) const {
    return {(u - cx) / fx, (v - cy) / fy, 1.0};
  }
  Eigen::Matrix3d K() const;
  bool InImage(double u, double v, double border = 0.0) const {
    return u >= border && v >= border && u <= width - 1 - border && v <= height - 1 - border;
  }

  // Camera for the image resized to new_width x new_height (pixel-centre
  // convention: a pixel centre at u maps to (u + 0.5) * s - 0.5).
  PinholeCamera Resized(int new_width, int new_height) const;
  // Camera for the sub-image starting at (x0, y0) of size w x h.
  PinholeCamera Cropped(int x0, int y0, int w, int h) const;
};

// A rectified stereo pair: both cameras share the intrinsics, the right camera
// sits `baseline` metres along +x of the left one (x_right = x_left - d).
struct StereoCamera {
  PinholeCamera left;      // intrinsics of both rectified images
  double baseline = 0.537; // metres between the optical centres (KITTI ~0.537)

  void Check() const;
  // fx * baseline: disparity (px) = FxB() * inverse depth (1/m).
  double FxB() const { return left.fx * baseline; }
  StereoCamera Resized(int new_width, int new_height) const;
  StereoCamera Cropped(int x0, int y0, int w, int h) const;
};

// DSO-style camera file ("Pinhole fx fy cx cy 0" / "w h" / "crop" / "w h"),
// with relative (fx/w ...) or absolute values, as DSO accepts. Only undistorted
// pinhole models are supported; anything else is an error naming the file.
PinholeCamera ReadDsoCameraFile(const std::string& path);
void WriteDsoCameraFile(const std::string& path, const PinholeCamera& camera);

}  // namespace dvso
