#include "core/alignment.h"

#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/error.h"

namespace dvso {

AlignmentMode ParseAlignmentMode(const std::string& name) {
  std::string lower = name;
  std::transform(lower.begin(), lower.end(), lower.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (lower == "none") return AlignmentMode::kNone;
  if (lower == "se3") return AlignmentMode::kSE3;
  if (lower == "sim3") return AlignmentMode::kSim3;
  throw Error("unknown alignment '" + name + "' (expected none, se3 or sim3)");
}

std::string AlignmentModeName(AlignmentMode mode) {
  switch (mode) {
    case AlignmentMode::kNone: return "none";
    case AlignmentMode::kSE3: return "se3";
    case AlignmentMode::kSim3: return "sim3";
  }
  return "unknown";
}

Eigen::Isometry3d Similarity3::Apply(const Eigen::Isometry3d& T_world_camera) const {
  Eigen::Isometry3d result = Eigen::Isometry3d::Identity();
  result.linear() = rotation * T_world_camera.linear();
  result.translation() = (*this) * T_world_camera.translation();
  return result;
}

Similarity3 UmeyamaAlignment(const std::vector<Eigen::Vector3d>& source,
                             const std::vector<Eigen::Vector3d>& target, AlignmentMode mode) {
  Require(source.size() == target.size(),
          "alignment needs equally many source and target points (" + std::to_string(source.size()) +
              " vs " + std::to_string(target.size()) + ")");
  Similarity3 result;
  if (mode == AlignmentMode::kNone) return result;
  Require(source.size() >= 3, "alignment needs at least 3 corresponding positions, got " +
                                  std::to_string(source.size()));
  const double n = static_cast<double>(source.size());

  Eigen::Vector3d mean_source = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_target = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < source.size(); ++i) {
    mean_source += source[i];
    mean_target += target[i];
  }
  mean_source /= n;
  mean_target /= n;

  // Cross-covariance Sigma = 1/n sum (y_i - mu_y)(x_i - mu_x)^T and the
  // source variance sigma_x^2 = 1/n sum ||x_i - mu_x||^2 (Umeyama eqs. 36-38).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double source_variance = 0.0;
  for (size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d x = source[i] - mean_source;
    const Eigen::Vector3d y = target[i] - mean_target;
    covariance += y * x.transpose();
    source_variance += x.squaredNorm();
  }
  covariance /= n;
  source_variance /= n;
  Require(source_variance > 1e-18,
          "alignment is degenerate: all estimated positions coincide (no motion to align)");

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU();
  const Eigen::Matrix3d V = svd.matrixV();
  // S flips the last axis when U V^T would be a reflection (eq. 39/43).
  Eigen::Vector3d s_diag(1.0, 1.0, 1.0);
  if (U.determinant() * V.determinant() < 0.0) s_diag(2) = -1.0;

  result.rotation = U * s_diag.asDiagonal() * V.transpose();
  if (mode == AlignmentMode::kSim3) {
    // c = tr(D S) / sigma_x^2 (eq. 42).
    result.scale = svd.singularValues().dot(s_diag) / source_variance;
    Require(std::isfinite(result.scale) && result.scale > 0.0,
            "Sim(3) alignment produced a non-positive scale (estimate and ground truth do not correspond)");
  }
  result.translation = mean_target - result.scale * result.rotation * mean_source;
  return result;
}

}  // namespace dvso
