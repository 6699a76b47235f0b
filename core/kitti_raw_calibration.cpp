#include "core/kitti_raw_calibration.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"

namespace dvso {

namespace fs = std::filesystem;

KittiCalibration ReadKittiCalibration(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open calibration file");
  KittiCalibration entries;
  std::string line;
  while (std::getline(in, line)) {
    const size_t colon = line.find(':');
    if (colon == std::string::npos) continue;
    std::istringstream values(line.substr(colon + 1));
    std::vector<double> numbers;
    double v = 0.0;
    while (values >> v) numbers.push_back(v);
    if (values.eof() && !numbers.empty()) entries[line.substr(0, colon)] = numbers;
  }
  return entries;
}

const std::vector<double>& CalibrationEntry(const KittiCalibration& calibration, const std::string& key, size_t count,
                                            const std::string& path) {
  const auto it = calibration.find(key);
  RequireFile(it != calibration.end() && it->second.size() == count, path,
              "needs a '" + key + ":' line with " + std::to_string(count) + " numbers");
  return it->second;
}

Eigen::Matrix3d RowMajor3x3(const std::vector<double>& v) {
  Eigen::Matrix3d m;
  m << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
  return m;
}

Eigen::Isometry3d ReadRigidCalibration(const std::string& path) {
  const KittiCalibration entries = ReadKittiCalibration(path);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = RowMajor3x3(CalibrationEntry(entries, "R", 9, path));
  const std::vector<double>& t = CalibrationEntry(entries, "T", 3, path);
  T.translation() << t[0], t[1], t[2];
  constexpr double kRotationTolerance = 1e-3;  // the files print 7 significant digits
  RequireFile((T.linear() * T.linear().transpose() - Eigen::Matrix3d::Identity()).norm() < kRotationTolerance, path,
              "R is not a rotation");
  return T;
}

RawCameraCalibration::RawCameraCalibration(const std::string& calib_dir)
    : dir(calib_dir), path((fs::path(calib_dir) / "calib_cam_to_cam.txt").string()), entries(ReadKittiCalibration(path)) {}

Eigen::Matrix<double, 3, 4> RawCameraCalibration::Projection(int camera) const {
  RequireFile(camera >= 0 && camera <= 3, path, "camera must be 0, 1, 2 or 3 (KITTI raw image_00..image_03)");
  const std::string key = "P_rect_0" + std::to_string(camera);
  const std::vector<double>& p = CalibrationEntry(entries, key, 12, path);
  RequireFile(p[0] > 0, path, key + " has no positive focal length");
  Eigen::Matrix<double, 3, 4> P;
  P << p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], p[8], p[9], p[10], p[11];
  return P;
}

Eigen::Isometry3d RawCameraCalibration::RectifiedFromVelodyne() const {
  Eigen::Isometry3d rectify = Eigen::Isometry3d::Identity();
  rectify.linear() = RowMajor3x3(CalibrationEntry(entries, "R_rect_00", 9, path));
  return rectify * ReadRigidCalibration((fs::path(dir) / "calib_velo_to_cam.txt").string());
}

std::string FindRawCalibrationDir(const std::string& drive_dir) {
  const std::string name = "calib_cam_to_cam.txt";
  for (const fs::path& dir : {fs::path(drive_dir), NormalizedFolderPath(drive_dir).parent_path()}) {
    if (fs::exists(dir / name)) return dir.string();
  }
  throw Error(drive_dir, "no " + name + " in the drive folder or its parent (KITTI raw date folder)");
}

}  // namespace dvso
