#include "vo/frontend/mono_initializer.h"
#include "vo/optimization/photometric_kernel.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/lie.h"
#include "vo/optimization/residual_pattern.h"

namespace dvso::vo {

void MonoInitializerOptions::Check() const {
  Require(min_frames >= 1, "mono_init min_frames must be >= 1");
  Require(max_frames > min_frames, "mono_init max_frames must be > min_frames");
  Require(min_parallax_px > 0, "mono_init min_parallax_px must be > 0");
  Require(regularization >= 0, "mono_init regularization must be >= 0");
  Require(iterations_per_level >= 1, "mono_init iterations_per_level must be >= 1");
  Require(translation_prior >= 0, "mono_init translation_prior must be >= 0");
}

MonoInitializer::MonoInitializer(const MonoInitializerOptions& options, const PixelSelectorOptions& selector,
                                 const CoarseTrackerOptions& tracker)
    : options_(options), selector_(selector), tracker_(tracker) {
  options_.Check();
  selector_.Check();
  tracker_.Check();
}

void MonoInitializer::SetFirstFrame(ImagePyramidPtr first) {
  first_ = std::move(first);
  points_.clear();
  neighbours_.clear();
  T_ = velocity_ = Eigen::Isometry3d::Identity();
  a_ = b_ = 0;
  frames_ = 0;
  failed_ = false;
  result_ = {};
  for (const SelectedPixel& p : SelectPixels(*first_, selector_)) {
    points_.push_back({static_cast<float>(p.x), static_cast<float>(p.y), 1.0, true});
  }
  // K nearest image neighbours for the smoothness prior (brute force, once).
  constexpr int kNeighbours = 6;
  const int n = static_cast<int>(points_.size());
  neighbours_.resize(n);
  std::vector<std::pair<float, int>> d(n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      const float dx = points_[i].u - points_[j].u, dy = points_[i].v - points_[j].v;
      d[j] = {i == j ? 1e30f : dx * dx + dy * dy, j};
    }
    const int k = std::min(kNeighbours, n - 1);
    if (k <= 0) continue;
    std::partial_sort(d.begin(), d.begin() + k, d.end());
    for (int m = 0; m < k; ++m) neighbours_[i].push_back(d[m].second);
  }
}

void MonoInitializer::ComputeNeighbourMeans(const std::vector<double>& idepths, std::vector<double>* means) const {
  means->resize(idepths.size());
  for (size_t i = 0; i < idepths.size(); ++i) {
    double sum = 0;
    for (int j : neighbours_[i]) sum += idepths[j];
    (*means)[i] = neighbours_[i].empty() ? idepths[i] : sum / neighbours_[i].size();
  }
}

double MonoInitializer::Evaluate(const ImagePyramid& frame, int level, const Eigen::Isometry3d& T, double a, double b,
                                 const std::vector<double>& idepths, bool want_system, Matrix8d* Hff, Vector8d* bf,
                                 std::vector<Vector8d>* Hfp, std::vector<double>* Hpp, std::vector<double>* bp,
                                 int* num) const {
  const PyramidLevel& host = first_->level(level);
  const PyramidLevel& target = frame.level(level);
  const PinholeCamera& cam = target.camera;
  const float fx = cam.fx, fy = cam.fy, cx = cam.cx, cy = cam.cy;
  const Eigen::Matrix3f R = T.linear().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  const float ea = std::exp(static_cast<float>(a));
  const float huber = tracker_.huber_threshold;
  const float c2 = tracker_.gradient_weight_c * tracker_.gradient_weight_c;
  const float oob_energy = huber * (2 * tracker_.cutoff_threshold - huber);
  const float scale = 1.0f / static_cast<float>(1 << level);
  double energy = 0;
  int count = 0;
  if (want_system) {
    Hff->setZero();
    bf->setZero();
    Hfp->assign(points_.size(), Vector8d::Zero());
    Hpp->assign(points_.size(), 0.0);
    bp->assign(points_.size(), 0.0);
  }
  for (size_t i = 0; i < points_.size(); ++i) {
    const float pu = (points_[i].u + 0.5f) * scale - 0.5f, pv = (points_[i].v + 0.5f) * scale - 0.5f;
    if (!host.InBounds(pu, pv, kPatternRadius + 1.5f)) continue;
    const float rho = static_cast<float>(idepths[i]);
    Eigen::Matrix<float, 8, 1> jf_acc_h = Eigen::Matrix<float, 8, 1>::Zero();
    float hpp = 0, bpp = 0;
    Eigen::Matrix<float, 8, 8> hff = Eigen::Matrix<float, 8, 8>::Zero();
    Eigen::Matrix<float, 8, 1> bff = Eigen::Matrix<float, 8, 1>::Zero();
    for (int k = 0; k < kPatternSize; ++k) {
      const float hu = pu + kPatternOffsets[k][0], hv = pv + kPatternOffsets[k][1];
      const float i_host = host.InterpolateIntensity(hu, hv);
      const Eigen::Vector3f ray((hu - cx) / fx, (hv - cy) / fy, 1.0f);
      const Eigen::Vector3f q = R * ray + t * rho;
      ++count;
      if (!(q.z() > 1e-4f)) {
        energy += oob_energy;
        continue;
      }
      const float iz = 1.0f / q.z();
      const float un = q.x() * iz, vn = q.y() * iz;
      const float u = fx * un + cx, v = fy * vn + cy;
      if (!target.InBounds(u, v, 1.5f)) {
        energy += oob_energy;
        continue;
      }
      const Eigen::Vector3f hit = target.Interpolate(u, v);
      const float r = hit[0] - ea * i_host - static_cast<float>(b);
      const float gx = hit[1], gy = hit[2];
      const float wg = GradientWeight(c2, gx, gy);
      float hw, huber_energy;
      HuberWeightAndEnergy(r, huber, &hw, &huber_energy);
      energy += wg * huber_energy;
      if (!want_system) continue;
      const float dxf = gx * fx, dyf = gy * fy;
      const Eigen::Matrix<float, 8, 1> J = PoseAffineJacobian(dxf, dyf, un, vn, rho * iz, ea, i_host);
      // d(u, v)/d rho: q depends on rho through t * rho.
      const float jp = dxf * (t.x() - un * t.z()) * iz + dyf * (t.y() - vn * t.z()) * iz;
      const float w = hw * wg;
      hff.noalias() += (w * J) * J.transpose();
      bff.noalias() += (w * r) * J;
      jf_acc_h += (w * jp) * J;
      hpp += w * jp * jp;
      bpp += w * r * jp;
    }
    if (want_system) {
      *Hff += hff.cast<double>();
      *bf += bff.cast<double>();
      (*Hfp)[i] = jf_acc_h.cast<double>();
      (*Hpp)[i] = hpp;
      (*bp)[i] = bpp;
    }
  }
  if (num) *num = count;
  return energy;
}

double MonoInitializer::MedianTranslationFlow(const Eigen::Isometry3d& T) const {
  const PinholeCamera& cam = first_->camera(0);
  std::vector<double> flows;
  flows.reserve(points_.size());
  for (const InitPoint& p : points_) {
    const Eigen::Vector3d q = cam.Unproject(p.u, p.v) + T.translation() * p.idepth;
    if (q.z() <= 1e-6) continue;
    const Eigen::Vector2d uv = cam.Project(q);
    flows.push_back(std::hypot(uv.x() - p.u, uv.y() - p.v));
  }
  if (flows.empty()) return 0;
  std::nth_element(flows.begin(), flows.begin() + flows.size() / 2, flows.end());
  return flows[flows.size() / 2];
}

Eigen::Matrix3d MonoInitializer::AlignRotation(const ImagePyramid& frame, const Eigen::Matrix3d& R_init, double* a,
                                               double* b) const {
  // Points at infinity (zero translation): the flow is the rotation's alone, so
  // depth and translation drop out; only [w, a, b] (rows 3..7) are solved.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_init;
  const std::vector<double> idepths(points_.size(), 1.0);
  Matrix8d Hff;
  Vector8d bf;
  std::vector<Vector8d> Hfp;
  std::vector<double> Hpp, bp;
  const int levels = std::min(frame.num_levels(), first_->num_levels());
  for (int l = levels - 1; l >= 0; --l) {
    double lambda = 0.1;
    double energy = Evaluate(frame, l, T, *a, *b, idepths, false, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr);
    for (int it = 0; it < options_.iterations_per_level; ++it) {
      Evaluate(frame, l, T, *a, *b, idepths, true, &Hff, &bf, &Hfp, &Hpp, &bp, nullptr);
      Eigen::Matrix<double, 5, 5> H = Hff.bottomRightCorner<5, 5>();
      for (int k = 0; k < 5; ++k) H(k, k) *= 1 + lambda;
      const Eigen::Matrix<double, 5, 1> dx = -H.ldlt().solve(bf.tail<5>());
      if (!dx.allFinite()) break;
      Vector8d step = Vector8d::Zero();
      step.tail<5>() = dx;
      Eigen::Isometry3d T_try = Orthonormalized(ExpSE3(step.head<6>()) * T);
      T_try.translation().setZero();
      const double a_try = *a + dx[3], b_try = *b + dx[4];
      const double e_try =
          Evaluate(frame, l, T_try, a_try, b_try, idepths, false, nullptr, nullptr, nullptr, nullptr, nullptr, nullptr);
      if (e_try < energy) {
        T = T_try;
        *a = a_try;
        *b = b_try;
        energy = e_try;
        lambda = std::max(lambda * 0.5, 1e-5);
      } else {
        lambda *= 4;
        if (lambda > 1e4) break;
      }
      if (dx.norm() < 1e-5) break;
    }
  }
  return T.linear();
}

MonoInitializer::Hypothesis MonoInitializer::RefineJointly(const ImagePyramid& frame, Hypothesis h) const {
  const int n = static_cast<int>(points_.size());
  std::vector<double>& idepths = h.idepths;
  Eigen::Isometry3d& T = h.T;
  double& a = h.a;
  double& b = h.b;
  std::vector<double> means;
  Matrix8d Hff;
  Vector8d bf;
  std::vector<Vector8d> Hfp;
  std::vector<double> Hpp, bp;
  const double reg = options_.regularization;
  // DSO's alpha term: prefer rotation over translation while the parallax is
  // small (a yaw and a sideways translation over a flat inverse depth produce
  // the same flow); real translation overcomes it once the flow demands it.
  const double translation_weight = options_.translation_prior * n;
  auto total_energy = [&](int level, const Eigen::Isometry3d& T_e, double a_e, double b_e,
                          const std::vector<double>& id, int* num) {
    double e = Evaluate(frame, level, T_e, a_e, b_e, id, false, nullptr, nullptr, nullptr, nullptr, nullptr, num);
    for (int i = 0; i < n; ++i) e += reg * (id[i] - means[i]) * (id[i] - means[i]);
    e += translation_weight * T_e.translation().squaredNorm();
    return e;
  };
  const int levels = std::min(frame.num_levels(), first_->num_levels());
  for (int l = levels - 1; l >= 0; --l) {
    double lambda = 0.1;
    ComputeNeighbourMeans(idepths, &means);
    int num = 0;
    double energy = total_energy(l, T, a, b, idepths, &num);
    for (int it = 0; it < options_.iterations_per_level; ++it) {
      Evaluate(frame, l, T, a, b, idepths, true, &Hff, &bf, &Hfp, &Hpp, &bp, nullptr);
      Matrix8d Hsc = Hff;
      Vector8d bsc = bf;
      std::vector<double> hpp_damped(n);
      for (int i = 0; i < n; ++i) {
        const double hd = (Hpp[i] + reg) * (1 + lambda) + 1e-6;
        const double g = bp[i] + reg * (idepths[i] - means[i]);
        hpp_damped[i] = hd;
        Hsc.noalias() -= Hfp[i] * Hfp[i].transpose() / hd;
        bsc.noalias() -= Hfp[i] * g / hd;
      }
      for (int k = 0; k < 3; ++k) {
        Hsc(k, k) += translation_weight;
        bsc(k) += translation_weight * T.translation()(k);
      }
      for (int k = 0; k < 8; ++k) Hsc(k, k) += lambda * Hff(k, k) + 1e-6;
      const Vector8d df = -Hsc.ldlt().solve(bsc);
      if (!df.allFinite()) break;
      std::vector<double> id_try(n);
      for (int i = 0; i < n; ++i) {
        const double g = bp[i] + reg * (idepths[i] - means[i]);
        id_try[i] = std::max(1e-3, idepths[i] - (g + Hfp[i].dot(df)) / hpp_damped[i]);
      }
      Eigen::Isometry3d T_try = Orthonormalized(ExpSE3(df.head<6>()) * T);
      const double a_try = a + df[6], b_try = b + df[7];
      // Gauge: mean inverse depth 1 (rescaling depths and translation together
      // leaves the photometric energy unchanged).
      double mean = 0;
      for (double v : id_try) mean += v;
      mean /= n;
      for (double& v : id_try) v /= mean;
      T_try.translation() *= mean;
      int num_try = 0;
      const double e_try = total_energy(l, T_try, a_try, b_try, id_try, &num_try);
      if (e_try < energy) {
        T = T_try;
        a = a_try;
        b = b_try;
        idepths.swap(id_try);
        energy = e_try;
        num = num_try;
        lambda = std::max(lambda * 0.5, 1e-5);
      } else {
        lambda *= 4;
        if (lambda > 1e4) break;
      }
      if (df.norm() < 1e-4) break;
    }
    h.energy = energy;
    h.num = std::max(num, 1);
  }
  return h;
}

bool MonoInitializer::AddFrame(const ImagePyramid& frame) {
  Require(first_ != nullptr, "MonoInitializer::AddFrame before SetFirstFrame");
  ++frames_;
  if (points_.size() < 50 || frames_ > options_.max_frames) {
    failed_ = true;
    return false;
  }
  const int n = static_cast<int>(points_.size());
  Hypothesis current;
  current.idepths.resize(n);
  for (int i = 0; i < n; ++i) current.idepths[i] = points_[i].idepth;
  const Eigen::Isometry3d T_prev = T_;
  current.T = velocity_ * T_;
  current.a = a_;
  current.b = b_;
  // Two starts for the joint optimisation, the lower energy wins:
  //  - constant velocity from the last estimate;
  //  - the same, but with the rotation aligned alone first (points at
  //    infinity): a turning start (yaw of a few degrees per
  //    frame, little parallax) otherwise tends to fall into the basin where a
  //    sideways translation over flat depths mimics the yaw, and the wrong
  //    motion then propagates through the constant-velocity prediction.
  Hypothesis rotation_first;
  rotation_first.a = a_;
  rotation_first.b = b_;
  rotation_first.T = current.T;
  rotation_first.T.linear() = AlignRotation(frame, current.T.linear(), &rotation_first.a, &rotation_first.b);
  rotation_first.idepths = current.idepths;
  current = RefineJointly(frame, std::move(current));
  rotation_first = RefineJointly(frame, std::move(rotation_first));
  const Hypothesis& best = rotation_first.energy < current.energy ? rotation_first : current;
  const std::vector<double>& idepths = best.idepths;
  const Eigen::Isometry3d T = best.T;
  const double a = best.a, b = best.b;
  const double last_energy = best.energy;
  const int last_num = best.num;
  const double rmse = std::sqrt(last_energy / last_num);
  if (!std::isfinite(rmse) || !T.matrix().allFinite() || !std::isfinite(a) || !std::isfinite(b)) {
    // Diverged: keep the last finite state, which the caller reads (T_last_first) to place the restart.
    failed_ = true;
    return false;
  }
  for (int i = 0; i < n; ++i) points_[i].idepth = idepths[i];
  velocity_ = Orthonormalized(T * T_prev.inverse());
  T_ = T;
  a_ = a;
  b_ = b;
  if (frames_ < options_.min_frames || MedianTranslationFlow(T) < options_.min_parallax_px) return false;

  // Success: keep the points whose own residuals are reasonable.
  result_ = {};
  result_.T_last_first = T;
  result_.affine_a = a;
  result_.affine_b = b;
  result_.rmse = rmse;
  const PyramidLevel& host = first_->level(0);
  const PyramidLevel& target = frame.level(0);
  const PinholeCamera& cam = target.camera;
  const float ea = std::exp(static_cast<float>(a));
  for (int i = 0; i < n; ++i) {
    const InitPoint& p = points_[i];
    double e = 0;
    bool ok = true;
    for (int k = 0; k < kPatternSize && ok; ++k) {
      const float hu = p.u + kPatternOffsets[k][0], hv = p.v + kPatternOffsets[k][1];
      const Eigen::Vector3d q = T * (cam.Unproject(hu, hv) / p.idepth);
      if (q.z() <= 1e-4) {
        ok = false;
        break;
      }
      const Eigen::Vector2d uv = cam.Project(q);
      if (!target.InBounds(uv.x(), uv.y(), 1.5f)) {
        ok = false;
        break;
      }
      const float r = target.InterpolateIntensity(uv.x(), uv.y()) - ea * host.InterpolateIntensity(hu, hv) - b;
      e += r * r;
    }
    if (ok && e / kPatternSize < 144.0 && p.idepth > 0) {
      result_.points.push_back({p.u, p.v, static_cast<float>(p.idepth)});
    }
  }
  if (result_.points.size() < 50) {
    failed_ = true;
    return false;
  }
  return true;
}

}  // namespace dvso::vo
