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
  // H_dd of each point: a trial linearisation overwrites it, and a rejected trial must not leave the
  // information of a state that was thrown away (the label filter and marginalisation read it).
  std::vector<std::pair<float, float>> idepth_hessians;  // (all residuals, temporal only)
  std::vector<std::pair<ResidualState, float>> residual_states;
};

StateBackup Backup(const std::vector<Keyframe>& kfs, const std::vector<PointRef>& refs) {
  StateBackup s;
  for (const Keyframe& kf : kfs) {
    s.poses.push_back(kf.world_to_camera);
    s.a.push_back(kf.a);
    s.b.push_back(kf.b);
  }
  for (const PointRef& r : refs) {
    const Point& p = kfs[r.host_index].points[r.point_index];
    s.idepths.push_back(p.idepth);
    s.idepth_hessians.emplace_back(p.idepth_hessian, p.idepth_hessian_temporal);
  }
  for (const Keyframe& kf : kfs) {
    for (const Point& p : kf.points) {
      for (const Residual& r : p.residuals) s.residual_states.emplace_back(r.state, r.energy);
    }
  }
  return s;
}

void Restore(const StateBackup& s, const std::vector<PointRef>& refs, std::vector<Keyframe>* kfs) {
  for (size_t i = 0; i < kfs->size(); ++i) {
    (*kfs)[i].world_to_camera = s.poses[i];
    (*kfs)[i].a = s.a[i];
    (*kfs)[i].b = s.b[i];
  }
  for (size_t i = 0; i < refs.size(); ++i) {
    Point& p = (*kfs)[refs[i].host_index].points[refs[i].point_index];
    p.idepth = s.idepths[i];
    p.idepth_hessian = s.idepth_hessians[i].first;
    p.idepth_hessian_temporal = s.idepth_hessians[i].second;
  }
  size_t k = 0;
  for (Keyframe& kf : *kfs) {
    for (Point& p : kf.points) {
      for (Residual& r : p.residuals) {
        r.state = s.residual_states[k].first;
        r.energy = s.residual_states[k].second;
        ++k;
      }
    }
  }
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
  residual_states_current_ = true;
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
    SyncFreeLinearizationPoints(&keyframes_);

    // Evaluate the trial state. Except on the last iteration this is the
    // next linearisation itself (residuals are evaluated once per
    // iteration); its comparable energy decides acceptance.
    const bool last = it + 1 == max_iterations;
    std::unique_ptr<WindowLinearizer> trial;
    double trial_comparable = 0.0, trial_active = 0.0;
    if (!last) {
      trial = std::make_unique<WindowLinearizer>(&keyframes_, camera_, options_);
      trial->Linearize(refs);
      trial_comparable = trial->comparable_energy();
      trial_active = trial->energy();
    } else {
      const WindowEnergy e = EvaluateWindowEnergy(&keyframes_, camera_, options_, true);
      trial_comparable = e.comparable;
      trial_active = e.active;
    }
    FramePriorTerms trial_priors = EvaluateFramePriors(keyframes_, prior_H_, prior_b_);
    const double trial_energy = trial_comparable + trial_priors.energy;
    if (!(trial_energy <= energy)) {
      Restore(backup, refs, &keyframes_);
      SyncFreeLinearizationPoints(&keyframes_);
      lambda = std::max(lambda * 4.0, 1e-6);
      if (lambda > 1e8) break;
      continue;
    }
    ++summary.accepted_steps;
    lambda = std::max(lambda * 0.25, 1e-9);
    const bool converged =
        (step.frames.norm() < options_.convergence_step &&
         std::sqrt(relative_depth_step_sq / std::max<size_t>(1, refs.size())) < options_.convergence_step) ||
        energy - trial_energy < options_.min_relative_decrease * energy;
    energy = trial_active + trial_priors.energy;
    priors = std::move(trial_priors);
    if (trial) {
      linearizer = std::move(trial);
      summary.num_active_residuals = linearizer->num_active_residuals();
    }
    if (converged) break;
  }
  summary.final_energy = energy;
  summary.total_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

int Window::RemoveOutliers() {
  // Optimize() leaves every residual's state evaluated at the final estimate;
  // re-evaluate only if the window changed since.
  if (!residual_states_current_) EvaluateWindowEnergy(&keyframes_, camera_, options_, true);
  int removed = 0;
  for (Keyframe& kf : keyframes_) {
    for (Point& p : kf.points) {
      for (const Residual& r : p.residuals) {
        if (r.kind == ResidualKind::kStaticStereo && r.state == ResidualState::kOutlier) {
          p.rejected_stereo_energy = r.energy;
        }
      }
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
