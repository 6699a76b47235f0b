#include "core/kitti_velodyne.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_raw_calibration.h"

namespace dvso {

namespace fs = std::filesystem;

namespace {
// Points closer than this ahead of the Velodyne (m, along its x axis) are dropped: behind the
// cameras or on the car itself (monodepth's generate_depth_map uses the same 0 m test on x >= 0).
constexpr float kMinForward = 0.0f;
constexpr int kFloatsPerPoint = 4;
}  // namespace

std::vector<VelodynePoint> ReadVelodyneTextScan(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open Velodyne scan");
  std::vector<VelodynePoint> points;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    std::istringstream values(line);
    VelodynePoint p;
    RequireFile(static_cast<bool>(values >> p.x() >> p.y() >> p.z() >> p.w()), path,
                "line " + std::to_string(line_number) + ": expected 'x y z reflectance'");
    points.push_back(p);
  }
  return points;
}

std::vector<VelodynePoint> ReadVelodyneScan(const std::string& path) {
  if (fs::path(path).extension() == ".txt") return ReadVelodyneTextScan(path);
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  RequireFile(in.good(), path, "cannot open Velodyne scan");
  const std::streamsize bytes = in.tellg();
  constexpr std::streamsize kPointBytes = kFloatsPerPoint * sizeof(float);
  RequireFile(bytes >= 0 && bytes % kPointBytes == 0, path,
              "a Velodyne .bin scan holds float32 x y z reflectance quadruples (size not a multiple of 16 bytes)");
  std::vector<VelodynePoint> points(static_cast<size_t>(bytes / kPointBytes));
  in.seekg(0);
  in.read(reinterpret_cast<char*>(points.data()), bytes);
  RequireFile(in.good() || bytes == 0, path, "read failed");
  return points;
}

void WriteVelodyneScan(const std::string& path, const std::vector<VelodynePoint>& points) {
  WriteStreamAtomically(
      path,
      [&](std::ostream& out) {
        out.write(reinterpret_cast<const char*>(points.data()),
                  static_cast<std::streamsize>(points.size() * kFloatsPerPoint * sizeof(float)));
      },
      /*binary=*/true);
}

VelodyneProjection ReadVelodyneProjection(const std::string& calib_dir, int camera) {
  const RawCameraCalibration calibration(calib_dir);
  VelodyneProjection projection;
  projection.velo_to_image = calibration.Projection(camera) * calibration.RectifiedFromVelodyne().matrix();
  const std::string key = "S_rect_0" + std::to_string(camera);
  const std::vector<double>& size = CalibrationEntry(calibration.entries, key, 2, calibration.path);
  projection.width = static_cast<int>(std::lround(size[0]));
  projection.height = static_cast<int>(std::lround(size[1]));
  RequireFile(projection.width > 0 && projection.height > 0, calibration.path, key + " is not an image size");
  return projection;
}

VelodyneDepthValue ParseVelodyneDepthValue(const std::string& name) {
  if (name == "velodyne-x") return VelodyneDepthValue::kVelodyneX;
  if (name == "camera-z") return VelodyneDepthValue::kCameraZ;
  throw Error("unknown depth value '" + name + "' (expected velodyne-x or camera-z)");
}

cv::Mat ProjectVelodyneDepth(const std::vector<VelodynePoint>& points, const VelodyneProjection& projection,
                             VelodyneDepthValue value) {
  cv::Mat depth(projection.height, projection.width, CV_32F, cv::Scalar(0));
  for (const VelodynePoint& point : points) {
    if (!(point.x() >= kMinForward)) continue;
    const Eigen::Vector3d x = projection.velo_to_image * Eigen::Vector4d(point.x(), point.y(), point.z(), 1.0);
    if (!(x.z() > 0)) continue;
    const long u = std::lround(x.x() / x.z()), v = std::lround(x.y() / x.z());
    if (u < 0 || v < 0 || u >= projection.width || v >= projection.height) continue;
    const double stored = value == VelodyneDepthValue::kVelodyneX ? static_cast<double>(point.x()) : x.z();
    // x_velo can be 0 (kMinForward) where z > 0: such a point is no depth (monodepth sets depth <= 0 to 0).
    if (!(stored > 0)) continue;
    float& d = depth.at<float>(static_cast<int>(v), static_cast<int>(u));
    if (d == 0 || stored < d) d = static_cast<float>(stored);
  }
  return depth;
}

}  // namespace dvso
