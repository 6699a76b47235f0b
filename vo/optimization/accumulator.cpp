#include "vo/optimization/accumulator.h"

#include <thread>

#include "core/error.h"

namespace dvso::vo {

namespace {
// Points whose depth Hessian is below this carry no depth information this
// iteration (all residuals out of bounds): they are left out of the Schur step.
constexpr double kMinDepthHessian = 1e-12;
// Points ahead whose target-image rows are prefetched.
constexpr size_t kPrefetchDistance = 4;

// Residual sources of a host in evaluation order: every other keyframe, then
// the host's right image, then its virtual stereo.
std::vector<std::pair<ResidualKind, int>> ResidualSlots(const WindowGeometry& geometry, int host_index) {
  std::vector<std::pair<ResidualKind, int>> slots;
  for (int t = 0; t < geometry.num_frames; ++t) {
    if (t != host_index) slots.emplace_back(ResidualKind::kTemporal, geometry.ids[t]);
  }
  slots.emplace_back(ResidualKind::kStaticStereo, geometry.ids[host_index]);
  slots.emplace_back(ResidualKind::kVirtualStereo, geometry.ids[host_index]);
  return slots;
}

Residual* FindResidual(Point* point, ResidualKind kind, int target_id) {
  for (Residual& r : point->residuals) {
    if (r.kind == kind && r.target_id == target_id) return &r;
  }
  return nullptr;
}

}  // namespace

struct WindowLinearizer::Partial {
  std::vector<PairBlock> pairs;
  double energy = 0.0;
  double comparable = 0.0;
  int active = 0;
};

std::vector<PointRef> CollectPoints(const std::vector<Keyframe>& keyframes, int host_index) {
  std::vector<PointRef> refs;
  for (int h = 0; h < static_cast<int>(keyframes.size()); ++h) {
    if (host_index >= 0 && h != host_index) continue;
    for (int i = 0; i < static_cast<int>(keyframes[h].points.size()); ++i) refs.push_back({h, i});
  }
  return refs;
}

WindowGeometry::WindowGeometry(const std::vector<Keyframe>& kfs, const StereoCamera& camera,
                               const WindowOptions& options) {
  num_frames = static_cast<int>(kfs.size());
  Require(num_frames <= 32, "WindowGeometry: at most 32 keyframes are supported");
  ids.resize(num_frames);
  for (int i = 0; i < num_frames; ++i) ids[i] = kfs[i].id;
  temporal.resize(static_cast<size_t>(num_frames) * num_frames);
  adjoint.resize(temporal.size(), Matrix6d::Identity());
  static_stereo.resize(num_frames);
  virtual_stereo.resize(num_frames);
  has_static.assign(num_frames, false);
  has_virtual.assign(num_frames, false);
  for (int h = 0; h < num_frames; ++h) {
    for (int t = 0; t < num_frames; ++t) {
      if (h == t) continue;
      temporal[h * num_frames + t] = TemporalGeometry(kfs[h], kfs[t], camera.left, options);
      const Eigen::Isometry3d T_th = options.first_estimate_jacobians
                                         ? RelativePose(kfs[t].world_to_camera_fej, kfs[h].world_to_camera_fej)
                                         : RelativePose(kfs[t].world_to_camera, kfs[h].world_to_camera);
      adjoint[h * num_frames + t] = Adjoint(T_th);
    }
    if (kfs[h].right && options.use_static_stereo) {
      static_stereo[h] = StaticStereoGeometry(kfs[h], camera, options);
      has_static[h] = true;
    }
    if (!kfs[h].right_disparity.empty() && options.use_virtual_stereo) {
      virtual_stereo[h] = VirtualStereoGeometry(kfs[h], camera.left, options);
      has_virtual[h] = true;
    }
  }
}

int WindowGeometry::IndexOf(int keyframe_id) const {
  for (int i = 0; i < num_frames; ++i) {
    if (ids[i] == keyframe_id) return i;
  }
  return -1;
}

const ResidualGeometry* WindowGeometry::For(int h, const Residual& residual, int* target_index) const {
  *target_index = h;
  switch (residual.kind) {
    case ResidualKind::kTemporal: {
      const int t = IndexOf(residual.target_id);
      if (t < 0 || t == h) return nullptr;
      *target_index = t;
      return &temporal[h * num_frames + t];
    }
    case ResidualKind::kStaticStereo:
      return has_static[h] ? &static_stereo[h] : nullptr;
    case ResidualKind::kVirtualStereo:
      return has_virtual[h] ? &virtual_stereo[h] : nullptr;
  }
  return nullptr;
}

WindowEnergy EvaluateWindowEnergy(std::vector<Keyframe>* keyframes, const StereoCamera& camera,
                                  const WindowOptions& options, bool write_states) {
  const WindowGeometry geometry(*keyframes, camera, options);
  WindowEnergy energy;
  ResidualEvaluation ev;
  for (int h = 0; h < geometry.num_frames; ++h) {
    std::vector<Point>& points = (*keyframes)[h].points;
    for (const auto& [kind, target_id] : ResidualSlots(geometry, h)) {
      Residual probe;
      probe.kind = kind;
      probe.target_id = target_id;
      int unused = 0;
      const ResidualGeometry* slot_geometry = geometry.For(h, probe, &unused);
      for (size_t i = 0; i < points.size(); ++i) {
        if (slot_geometry != nullptr && i + kPrefetchDistance < points.size()) {
          PrefetchResidual(*slot_geometry, points[i + kPrefetchDistance], points[i + kPrefetchDistance].idepth);
        }
        Point& point = points[i];
        Residual* residual = FindResidual(&point, kind, target_id);
        if (residual == nullptr) continue;
        int t = 0;
        const ResidualGeometry* g = geometry.For(h, *residual, &t);
        ev.state = ResidualState::kOutOfBounds;
        ev.energy = 0.0f;
        if (g != nullptr) {
          ev.state = ResidualState::kActive;
          EvaluateResidual(*g, point, point.idepth, options, false, &ev);
        }
        if (residual->state == ResidualState::kActive) {
          const float cap = CappedResidualEnergy(options, kind);
          energy.comparable += ev.state == ResidualState::kOutOfBounds ? cap : std::min(ev.energy, cap);
        }
        if (ev.state == ResidualState::kActive) energy.active += ev.energy;
        if (write_states) {
          residual->state = ev.state;
          residual->energy = ev.state == ResidualState::kOutOfBounds ? 0.0f : ev.energy;
        }
      }
    }
  }
  return energy;
}

WindowLinearizer::WindowLinearizer(std::vector<Keyframe>* keyframes, const StereoCamera& camera,
                                   const WindowOptions& options)
    : keyframes_(keyframes),
      camera_(camera),
      options_(options),
      geometry_(*keyframes, camera, options),
      num_frames_(static_cast<int>(keyframes->size())) {}

void WindowLinearizer::Linearize(const std::vector<PointRef>& points) {
  points_ = points;
  const int nfp = num_frame_params();
  point_blocks_.assign(points_.size(), PointBlock());
  point_cross_.assign(points_.size() * nfp, 0.0);
  const int threads = std::max(1, std::min(options_.num_threads, static_cast<int>(points_.size() / 256) + 1));
  std::vector<Partial> partials(threads);
  for (Partial& p : partials) p.pairs.assign(geometry_.temporal.size(), PairBlock());
  if (threads == 1) {
    LinearizeRange(0, points_.size(), &partials[0]);
  } else {
    std::vector<std::thread> workers;
    const size_t chunk = (points_.size() + threads - 1) / threads;
    for (int t = 0; t < threads; ++t) {
      const size_t begin = std::min(points_.size(), t * chunk);
      const size_t end = std::min(points_.size(), begin + chunk);
      workers.emplace_back([this, begin, end, &partials, t] { LinearizeRange(begin, end, &partials[t]); });
    }
    for (std::thread& w : workers) w.join();
  }
  pairs_ = std::move(partials[0].pairs);
  energy_ = partials[0].energy;
  comparable_energy_ = partials[0].comparable;
  num_active_ = partials[0].active;
  for (int t = 1; t < threads; ++t) {
    for (size_t k = 0; k < pairs_.size(); ++k) {
      pairs_[k].H += partials[t].pairs[k].H;
      pairs_[k].b += partials[t].pairs[k].b;
    }
    energy_ += partials[t].energy;
    comparable_energy_ += partials[t].comparable;
    num_active_ += partials[t].active;
  }
  AssembleFrameBlocks();
}

void WindowLinearizer::LinearizeRange(size_t begin, size_t end, Partial* partial) {
  std::vector<Keyframe>& kfs = *keyframes_;
  ResidualEvaluation ev;
  // Target-major order within each host: all points of a host against one
  // target image, then the next, so that image reads stay cache-local.
  size_t run_begin = begin;
  while (run_begin < end) {
    const int h = points_[run_begin].host_index;
    size_t run_end = run_begin;
    while (run_end < end && points_[run_end].host_index == h) ++run_end;
    for (const auto& [kind, target_id] : ResidualSlots(geometry_, h)) {
      const ResidualGeometry* slot_geometry = nullptr;
      {
        Residual probe;
        probe.kind = kind;
        probe.target_id = target_id;
        int unused = 0;
        slot_geometry = geometry_.For(h, probe, &unused);
      }
      for (size_t i = run_begin; i < run_end; ++i) {
        if (slot_geometry != nullptr && i + kPrefetchDistance < run_end) {
          const Point& ahead = kfs[h].points[points_[i + kPrefetchDistance].point_index];
          PrefetchResidual(*slot_geometry, ahead, ahead.idepth);
        }
        Point& point = kfs[h].points[points_[i].point_index];
        Residual* residual = FindResidual(&point, kind, target_id);
        if (residual != nullptr) ProcessResidual(i, h, &point, residual, partial, &ev);
      }
    }
    for (size_t i = run_begin; i < run_end; ++i) {
      Point& p = kfs[h].points[points_[i].point_index];
      p.idepth_hessian = static_cast<float>(point_blocks_[i].H_dd);
      p.idepth_hessian_temporal = static_cast<float>(point_blocks_[i].H_dd_temporal);
    }
    run_begin = run_end;
  }
}

void WindowLinearizer::ProcessResidual(size_t i, int h, Point* point_ptr, Residual* residual_ptr, Partial* partial,
                                       ResidualEvaluation* ev_ptr) {
  Point& point = *point_ptr;
  Residual& residual = *residual_ptr;
  ResidualEvaluation& ev = *ev_ptr;
  PointBlock& block = point_blocks_[i];
  double* cross = point_cross_.data() + i * num_frame_params();
  int t = h;
  const ResidualGeometry* geometry = geometry_.For(h, residual, &t);
  const bool was_active = residual.state == ResidualState::kActive;
  if (geometry == nullptr) {
    residual.state = ResidualState::kOutOfBounds;
    if (was_active) partial->comparable += CappedResidualEnergy(options_, residual.kind);
    return;
  }
  ev.state = ResidualState::kActive;
  EvaluateResidual(*geometry, point, point.idepth, options_, true, &ev);
  residual.state = ev.state;
  residual.energy = ev.state == ResidualState::kOutOfBounds ? 0.0f : ev.energy;
  if (was_active) {
    const float cap = CappedResidualEnergy(options_, residual.kind);
    partial->comparable += ev.state == ResidualState::kOutOfBounds ? cap : std::min(ev.energy, cap);
  }
  if (ev.state != ResidualState::kActive) return;
  partial->energy += ev.energy;
  ++partial->active;

  const Eigen::Matrix<float, kPatternSize, 1> wd = ev.weight.cwiseProduct(ev.J_idepth);
  const double h_dd = wd.dot(ev.J_idepth);
  block.H_dd += h_dd;
  if (residual.kind == ResidualKind::kTemporal) block.H_dd_temporal += h_dd;
  block.b_d += wd.dot(ev.r);
  if (!geometry->has_frame_jacobians) return;

  const Eigen::Matrix<float, kPairParams, kPatternSize> Jw = ev.J_pair.transpose() * ev.weight.asDiagonal();
  PairBlock& pair = partial->pairs[h * num_frames_ + t];
  pair.H.noalias() += Jw.lazyProduct(ev.J_pair).cast<double>();
  pair.b.noalias() += (Jw * ev.r).cast<double>();
  const Eigen::Matrix<double, kPairParams, 1> h_yd = (Jw * ev.J_idepth).cast<double>();
  // Cross terms in absolute parameters: host pose through -Adj(T_th)^T.
  Eigen::Map<Vector8d> host_cross(cross + kFrameParams * h);
  Eigen::Map<Vector8d> target_cross(cross + kFrameParams * t);
  host_cross.head<6>() -= geometry_.adjoint[h * num_frames_ + t].transpose() * h_yd.head<6>();
  host_cross.tail<2>() += h_yd.segment<2>(6);
  target_cross.head<6>() += h_yd.head<6>();
  target_cross.tail<2>() += h_yd.segment<2>(8);
  block.frame_mask |= (1u << h) | (1u << t);
}

void WindowLinearizer::AssembleFrameBlocks() {
  const int nfp = num_frame_params();
  H_frames_.setZero(nfp, nfp);
  b_frames_.setZero(nfp);
  for (int h = 0; h < num_frames_; ++h) {
    for (int t = 0; t < num_frames_; ++t) {
      if (h == t) continue;
      const PairBlock& pair = pairs_[h * num_frames_ + t];
      if (pair.H.diagonal().isZero(0.0)) continue;
      // y = A_h x_h + A_t x_t (relative twist and the four affine parameters).
      Eigen::Matrix<double, kPairParams, kFrameParams> A_h = Eigen::Matrix<double, kPairParams, kFrameParams>::Zero();
      Eigen::Matrix<double, kPairParams, kFrameParams> A_t = Eigen::Matrix<double, kPairParams, kFrameParams>::Zero();
      A_h.topLeftCorner<6, 6>() = -geometry_.adjoint[h * num_frames_ + t];
      A_h(6, 6) = 1.0;
      A_h(7, 7) = 1.0;
      A_t.topLeftCorner<6, 6>().setIdentity();
      A_t(8, 6) = 1.0;
      A_t(9, 7) = 1.0;
      const Eigen::Matrix<double, kPairParams, kFrameParams> HA_h = pair.H * A_h;
      const Eigen::Matrix<double, kPairParams, kFrameParams> HA_t = pair.H * A_t;
      H_frames_.block<8, 8>(8 * h, 8 * h) += A_h.transpose() * HA_h;
      H_frames_.block<8, 8>(8 * t, 8 * t) += A_t.transpose() * HA_t;
      const Matrix8d H_ht = A_h.transpose() * HA_t;
      H_frames_.block<8, 8>(8 * h, 8 * t) += H_ht;
      H_frames_.block<8, 8>(8 * t, 8 * h) += H_ht.transpose();
      b_frames_.segment<8>(8 * h) += A_h.transpose() * pair.b;
      b_frames_.segment<8>(8 * t) += A_t.transpose() * pair.b;
    }
  }
}

void WindowLinearizer::Reduce(double lambda, const Eigen::MatrixXd& extra_H, const Eigen::VectorXd& extra_b,
                              Eigen::MatrixXd* H, Eigen::VectorXd* b) const {
  const int nfp = num_frame_params();
  *H = H_frames_;
  *b = b_frames_;
  if (extra_H.size() > 0) *H += extra_H;
  if (extra_b.size() > 0) *b += extra_b;
  H->diagonal() *= (1.0 + lambda);
  int frames[32];
  for (size_t i = 0; i < points_.size(); ++i) {
    const PointBlock& block = point_blocks_[i];
    if (block.H_dd < kMinDepthHessian || block.frame_mask == 0) continue;
    const double inv = 1.0 / (block.H_dd * (1.0 + lambda));
    int m = 0;
    for (int f = 0; f < num_frames_; ++f) {
      if (block.frame_mask & (1u << f)) frames[m++] = f;
    }
    const double* cross = point_cross_.data() + i * nfp;
    for (int a = 0; a < m; ++a) {
      const Eigen::Map<const Vector8d> ca(cross + kFrameParams * frames[a]);
      b->segment<8>(8 * frames[a]) -= ca * (block.b_d * inv);
      for (int c = a; c < m; ++c) {
        const Eigen::Map<const Vector8d> cc(cross + kFrameParams * frames[c]);
        H->block<8, 8>(8 * frames[a], 8 * frames[c]).noalias() -= (ca * inv) * cc.transpose();
      }
    }
  }
  // Only the upper block triangle was updated (diagonal blocks fully).
  H->triangularView<Eigen::StrictlyLower>() = H->transpose();
}

std::vector<double> WindowLinearizer::BackSubstitute(const Eigen::VectorXd& dx, double lambda) const {
  const int nfp = num_frame_params();
  std::vector<double> dd(points_.size(), 0.0);
  for (size_t i = 0; i < points_.size(); ++i) {
    const PointBlock& block = point_blocks_[i];
    if (block.H_dd < kMinDepthHessian) continue;
    const Eigen::Map<const Eigen::VectorXd> cross(point_cross_.data() + i * nfp, nfp);
    dd[i] = -(block.b_d + cross.dot(dx)) / (block.H_dd * (1.0 + lambda));
  }
  return dd;
}

void WindowLinearizer::FullSystem(Eigen::MatrixXd* H, Eigen::VectorXd* b) const {
  const int nfp = num_frame_params();
  const int n = nfp + static_cast<int>(points_.size());
  H->setZero(n, n);
  b->setZero(n);
  H->topLeftCorner(nfp, nfp) = H_frames_;
  b->head(nfp) = b_frames_;
  for (size_t i = 0; i < points_.size(); ++i) {
    const int k = nfp + static_cast<int>(i);
    const Eigen::Map<const Eigen::VectorXd> cross(point_cross_.data() + i * nfp, nfp);
    (*H)(k, k) = point_blocks_[i].H_dd;
    (*b)(k) = point_blocks_[i].b_d;
    H->block(0, k, nfp, 1) = cross;
    H->block(k, 0, 1, nfp) = cross.transpose();
  }
}

}  // namespace dvso::vo
