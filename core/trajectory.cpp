#include "core/trajectory.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/lie.h"

namespace dvso {

double Trajectory::PathLength() const {
  double length = 0.0;
  for (size_t i = 1; i < poses.size(); ++i) {
    length += (poses[i].T_world_camera.translation() - poses[i - 1].T_world_camera.translation()).norm();
  }
  return length;
}

namespace {

bool ParseLine(const std::string& line, std::vector<double>* values) {
  values->clear();
  std::istringstream in(line);
  std::string token;
  while (in >> token) {
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || !std::isfinite(v)) return false;
    values->push_back(v);
  }
  return true;
}

// A printed rotation is orthonormal to its printed digits (KITTI's GT, 7 significant digits: ~2e-7; our
// writers, 12 digits: ~1e-12). Beyond this the 3x3 block is no rotation (scaled, sheared, a reflection,
// numbers in the wrong columns), and every metric on it would be meaningless.
constexpr double kRotationTolerance = 1e-3;
// A printed unit quaternion has norm 1 to its digits; one further off (e.g. qw = 0.001 for "no rotation")
// is no rotation that normalising could recover with confidence.
constexpr double kQuaternionNormTolerance = 1e-2;

bool IsBlankOrComment(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first == std::string::npos || line[first] == '#';
}

}  // namespace

Trajectory ReadTrajectory(const std::string& path, TrajectoryFormat format,
                          const std::vector<double>* times) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open trajectory file");
  Trajectory trajectory;
  std::string line;
  std::vector<double> v;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (IsBlankOrComment(line)) continue;
    const std::string where = "line " + std::to_string(line_number);
    RequireFile(ParseLine(line, &v), path, where + ": not a list of finite numbers");
    if (format == TrajectoryFormat::kAuto) {
      RequireFile(v.size() == 12 || v.size() == 8, path,
                  where + ": expected 12 (KITTI) or 8 (TUM) numbers, got " + std::to_string(v.size()));
      format = v.size() == 12 ? TrajectoryFormat::kKitti : TrajectoryFormat::kTum;
    }
    StampedPose pose;
    if (format == TrajectoryFormat::kKitti) {
      RequireFile(v.size() == 12, path, where + ": KITTI pose needs 12 numbers");
      pose.T_world_camera = IsometryFromRowMajor3x4(v.data());
      const Eigen::Matrix3d R = pose.T_world_camera.linear();
      const double orthogonality = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
      const double determinant = R.determinant();
      RequireFile(orthogonality <= kRotationTolerance && std::abs(determinant - 1.0) <= kRotationTolerance, path,
                  where + ": the 3x3 part is not a rotation (max |R^T R - I| = " + std::to_string(orthogonality) +
                      ", det R = " + std::to_string(determinant) + "; tolerance " +
                      std::to_string(kRotationTolerance) + ")");
      pose.timestamp = static_cast<double>(trajectory.poses.size());
    } else {
      RequireFile(v.size() == 8, path, where + ": TUM pose needs 8 numbers");
      Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
      RequireFile(std::abs(q.norm() - 1.0) <= kQuaternionNormTolerance, path,
                  where + ": quaternion (qx qy qz qw) of norm " + std::to_string(q.norm()) +
                      ", not a unit quaternion (tolerance " + std::to_string(kQuaternionNormTolerance) + ")");
      q.normalize();  // the printed digits' rounding
      pose.timestamp = v[0];
      pose.T_world_camera.linear() = q.toRotationMatrix();
      pose.T_world_camera.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    }
    trajectory.poses.push_back(pose);
  }
  RequireFile(!trajectory.empty(), path, "trajectory file holds no poses");
  // A TUM file carries its own timestamps: a times file beside it would be silently ignored, so it is an error.
  RequireFile(times == nullptr || format == TrajectoryFormat::kKitti, path,
              "is a TUM trajectory with its own timestamps: a times file applies only to KITTI-format files");
  if (times != nullptr) {
    RequireFile(times->size() == trajectory.size(), path,
                "times file has " + std::to_string(times->size()) + " entries for " +
                    std::to_string(trajectory.size()) + " poses");
    for (size_t i = 0; i < trajectory.size(); ++i) trajectory.poses[i].timestamp = (*times)[i];
  }
  return trajectory;
}

void WriteKittiTrajectory(const std::string& path, const Trajectory& trajectory) {
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out << std::setprecision(12);
    for (const auto& p : trajectory.poses) {
      const Eigen::Matrix3d R = p.T_world_camera.linear();
      const Eigen::Vector3d t = p.T_world_camera.translation();
      for (int r = 0; r < 3; ++r) {
        out << R(r, 0) << ' ' << R(r, 1) << ' ' << R(r, 2) << ' ' << t(r) << (r < 2 ? ' ' : '\n');
      }
    }
  });
}

void WriteTumTrajectory(const std::string& path, const Trajectory& trajectory) {
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out << std::setprecision(12);
    for (const auto& p : trajectory.poses) {
      const Eigen::Quaterniond q(p.T_world_camera.linear());
      const Eigen::Vector3d t = p.T_world_camera.translation();
      // Timestamps get fixed nanosecond precision: Unix times (~1.5e9 s) need
      // more than 12 significant digits.
      out << std::fixed << std::setprecision(9) << p.timestamp << std::defaultfloat << std::setprecision(12)
          << ' ' << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' '
          << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
    }
  });
}

std::vector<double> ReadTimes(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open times file");
  std::vector<double> times;
  std::string line;
  int line_number = 0;
  std::vector<double> v;
  while (std::getline(in, line)) {
    ++line_number;
    if (IsBlankOrComment(line)) continue;
    RequireFile(ParseLine(line, &v) && v.size() == 1, path,
                "line " + std::to_string(line_number) + ": expected one timestamp");
    times.push_back(v[0]);
  }
  return times;
}

}  // namespace dvso
