// The Levenberg-Marquardt loop of the windowed photometric bundle adjustment
// (paper section 4: "jointly optimized using the Gauss Newton method", with
// DSO's Schur complement on the inverse depths).
//
// One iteration: linearise all residuals (Jacobians at the current state, pose
// Jacobians at the first estimates), add the frame priors (marginalisation
// prior + gauge/affine priors), eliminate the inverse depths, solve the
// reduced camera system, back-substitute, and accept the step only if the
// total energy decreases (else restore and increase the damping).
#include <chrono>
#include <cmath>
#include <memory>

#include "vo/optimization/accumulator.h"
#include "vo/optimization/marginalization.h"
#include "vo/optimization/schur_solver.h"
#include "vo/optimization/window.h"

namespace dvso::vo {
namespace {

struct StateBackup {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<double> a, b;
  std::vector<double> idepths;
};

StateBackup Backup(const std::vector<Keyframe>& kfs, const std::vector<PointRef>& refs) {
  StateBackup s;
  for (const Keyframe& kf : kfs) {
    s.poses.push_back(kf.world_to_camera);
    s.a.push_back(kf.a);
    s.b.push_back(kf.b);
  }
  for (const PointRef& r : refs) s.idepths.push_back(kfs[r.host_index].points[r.point_index].idepth);
  return s;
}

void Restore(const StateBackup& s, const std::vector<PointRef>& refs, std::vector<Keyframe>* kfs) {
  for (size_t i = 0; i < kfs->size(); ++i) {
    (*kfs)[i].world_to_camera = s.poses[i];
    (*kfs)[i].a = s.a[i];
    (*kfs)[i].b = s.b[i];
  }
  for (size_t i = 0; i < refs.size(); ++i) (*kfs)[refs[i].host_index].points[refs[i].point_index].idepth = s.idepths[i];
}

}  // namespace

OptimizationSummary Window::Optimize(int max_iterations) {
  const auto start = std::chrono::steady_clock::now();
  OptimizationSummary summary;
  if (keyframes_.empty()) return summary;
  const std::vector<PointRef> refs = CollectPoints(keyframes_);
  SyncFreeLinearizationPoints(&keyframes_);

  auto linearizer = std::make_unique<WindowLinearizer>(&keyframes_, camera_, options_);
  linearizer->Linearize(refs);
  FramePriorTerms priors = EvaluateFramePriors(keyframes_, prior_H_, prior_b_);
  double energy = linearizer->energy() + priors.energy;
  summary.initial_energy = energy;
  summary.num_active_residuals = linearizer->num_active_residuals();
  double lambda = options_.initial_lambda;

  for (int it = 0; it < max_iterations; ++it) {
    ++summary.iterations;
    WindowStep step;
    if (!SolveWindowStep(*linearizer, lambda, priors.H, priors.b, &step)) {
      lambda = std::max(lambda * 10.0, 1e-4);
      continue;
    }
    const StateBackup backup = Backup(keyframes_, refs);
    for (int i = 0; i < num_keyframes(); ++i) {
      Keyframe& kf = keyframes_[i];
      ApplyFrameUpdate(step.frames.segment<kFrameParams>(kFrameParams * i), &kf.world_to_camera, &kf.a, &kf.b);
    }
    double relative_depth_step_sq = 0.0;
    for (size_t i = 0; i < refs.size(); ++i) {
      Point& p = keyframes_[refs[i].host_index].points[refs[i].point_index];
      const double old = p.idepth;
      p.idepth = std::max(options_.min_idepth, p.idepth + step.depths[i]);
      const double rel = (p.idepth - old) / std::max(old, 1e-3);
      relative_depth_step_sq += rel * rel;
    }
    const double trial_energy = EvaluateWindowEnergy(&keyframes_, camera_, options_, false) +
                                EvaluateFramePriors(keyframes_, prior_H_, prior_b_).energy;
    if (!(trial_energy <= energy)) {
      Restore(backup, refs, &keyframes_);
      lambda = std::max(lambda * 4.0, 1e-6);
      if (lambda > 1e8) break;
      continue;
    }
    ++summary.accepted_steps;
    SyncFreeLinearizationPoints(&keyframes_);
    lambda = std::max(lambda * 0.25, 1e-9);
    const bool converged =
        step.frames.norm() < options_.convergence_step &&
        std::sqrt(relative_depth_step_sq / std::max<size_t>(1, refs.size())) < options_.convergence_step;
    energy = trial_energy;
    if (converged || it + 1 == max_iterations) break;
    linearizer = std::make_unique<WindowLinearizer>(&keyframes_, camera_, options_);
    linearizer->Linearize(refs);
    priors = EvaluateFramePriors(keyframes_, prior_H_, prior_b_);
    energy = linearizer->energy() + priors.energy;
    summary.num_active_residuals = linearizer->num_active_residuals();
  }
  summary.final_energy = energy;
  summary.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

int Window::RemoveOutliers() {
  EvaluateWindowEnergy(&keyframes_, camera_, options_, true);
  int removed = 0;
  for (Keyframe& kf : keyframes_) {
    for (Point& p : kf.points) {
      p.residuals.erase(std::remove_if(p.residuals.begin(), p.residuals.end(),
                                       [](const Residual& r) { return r.state != ResidualState::kActive; }),
                        p.residuals.end());
    }
    const size_t before = kf.points.size();
    kf.points.erase(std::remove_if(kf.points.begin(), kf.points.end(),
                                   [](const Point& p) { return p.residuals.empty(); }),
                    kf.points.end());
    removed += static_cast<int>(before - kf.points.size());
  }
  return removed;
}

}  // namespace dvso::vo
