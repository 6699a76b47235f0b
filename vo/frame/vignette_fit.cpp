#include "vo/frame/vignette_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/statistics.h"

namespace dvso::vo {

void VignetteFitOptions::Check() const {
  Require(num_coefficients >= 0 && num_coefficients <= 4, "vignette fit: num_coefficients (--coefficients) must be in [0, 4]");
  Require(huber_threshold > 0, "vignette fit: huber_threshold must be > 0");
  Require(max_iterations >= 1, "vignette fit: max_iterations must be >= 1");
  Require(min_observations_per_point >= 2, "vignette fit: min_observations_per_point must be >= 2");
}

namespace {

// Levenberg-Marquardt damping: start, growth on a rejected step, shrink on an accepted one.
constexpr double kInitialDamping = 1e-4;
constexpr double kDampingGrowth = 10.0;
constexpr double kDampingShrink = 3.0;
constexpr double kMaxDamping = 1e8;
// Relative cost decrease below which the fit has converged.
constexpr double kConvergedDecrease = 1e-9;

struct Problem {
  // Observations grouped by point: point_begin[p] .. point_begin[p + 1] in `obs`.
  std::vector<VignetteObservation> obs;
  std::vector<int> point_begin;
  int num_frames = 0;
  int num_points() const { return static_cast<int>(point_begin.size()) - 1; }
};

struct State {
  std::vector<double> gain, bias, radiance;
  RadialVignette vignette;
};

double Residual(const State& s, const VignetteObservation& o) {
  return s.gain[o.frame] * s.vignette.At(o.rho_sq) * s.radiance[o.point] + s.bias[o.frame] - o.intensity;
}

double HuberCost(double r, double k) {
  const double a = std::abs(r);
  return a <= k ? 0.5 * r * r : k * (a - 0.5 * k);
}

double HuberWeight(double r, double k) {
  const double a = std::abs(r);
  return a <= k ? 1.0 : k / a;
}

double Cost(const Problem& problem, const State& s, double k) {
  double cost = 0;
  for (const VignetteObservation& o : problem.obs) cost += HuberCost(Residual(s, o), k);
  return cost;
}

// Minimises sum_o Huber(r_o) over a_1.., b, c and R by Levenberg-Marquardt; R is eliminated in every
// step (each point's radiance couples only to its own observations' frames and to c).
int Minimise(const Problem& problem, const VignetteFitOptions& options, State* state) {
  const int F = problem.num_frames, n = static_cast<int>(state->vignette.coefficients.size());
  const int dim = 2 * F - 1 + n;  // [a_1 .. a_{F-1}, b_0 .. b_{F-1}, c_1 .. c_n]
  auto gain_index = [](int f) { return f - 1; };  // a_0 = 1 is not a parameter (scale gauge)
  auto bias_index = [F](int f) { return F - 1 + f; };
  auto coefficient_index = [F](int i) { return 2 * F - 1 + i; };
  const double k = options.huber_threshold;
  double damping = kInitialDamping;
  double cost = Cost(problem, *state, k);
  int iteration = 0;
  for (; iteration < options.max_iterations; ++iteration) {
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(dim, dim);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
    // Per point: its radiance block and its coupling row h (sparse: the frames it is seen in, and c).
    std::vector<double> h_rr(problem.num_points()), g_r(problem.num_points());
    std::vector<std::vector<std::pair<int, double>>> coupling(problem.num_points());
    std::vector<std::pair<int, double>> jx;  // one observation's Jacobian over x
    for (int p = 0; p < problem.num_points(); ++p) {
      std::vector<std::pair<int, double>>& h = coupling[p];
      std::vector<double> h_c(n, 0.0);
      for (int j = problem.point_begin[p]; j < problem.point_begin[p + 1]; ++j) {
        const VignetteObservation& o = problem.obs[j];
        const double v = state->vignette.At(o.rho_sq), a = state->gain[o.frame], radiance = state->radiance[p];
        const double r = a * v * radiance + state->bias[o.frame] - o.intensity;
        const double w = HuberWeight(r, k);
        const double j_r = a * v;
        jx.clear();
        if (o.frame > 0) jx.emplace_back(gain_index(o.frame), v * radiance);
        jx.emplace_back(bias_index(o.frame), 1.0);
        for (int i = 0; i < n; ++i) jx.emplace_back(coefficient_index(i), a * radiance * state->vignette.Derivative(i, o.rho_sq));
        for (const auto& [ia, va] : jx) {
          g[ia] += w * va * r;
          for (const auto& [ib, vb] : jx) H(ia, ib) += w * va * vb;
        }
        h_rr[p] += w * j_r * j_r;
        g_r[p] += w * j_r * r;
        if (o.frame > 0) h.emplace_back(gain_index(o.frame), w * j_r * v * radiance);
        h.emplace_back(bias_index(o.frame), w * j_r);
        const size_t first_coefficient = jx.size() - n;  // jx ends with the coefficients' Jacobians
        for (int i = 0; i < n; ++i) h_c[i] += w * j_r * jx[first_coefficient + i].second;
      }
      for (int i = 0; i < n; ++i) h.emplace_back(coefficient_index(i), h_c[i]);
    }
    const Eigen::MatrixXd H_undamped = H;
    const Eigen::VectorXd g_undamped = g;
    bool accepted = false;
    while (!accepted && damping < kMaxDamping) {
      // Schur complement of the damped radiance blocks.
      Eigen::MatrixXd S = H_undamped;
      Eigen::VectorXd b = g_undamped;
      for (int i = 0; i < dim; ++i) S(i, i) += damping * (H_undamped(i, i) + 1e-9);
      std::vector<double> h_rr_damped(problem.num_points());
      for (int p = 0; p < problem.num_points(); ++p) {
        h_rr_damped[p] = h_rr[p] * (1.0 + damping) + 1e-12;
        const double inv = 1.0 / h_rr_damped[p];
        for (const auto& [ia, va] : coupling[p]) {
          b[ia] -= va * g_r[p] * inv;
          for (const auto& [ib, vb] : coupling[p]) S(ia, ib) -= va * vb * inv;
        }
      }
      const Eigen::VectorXd dx = -S.ldlt().solve(b);
      State trial = *state;
      for (int f = 1; f < F; ++f) trial.gain[f] += dx[gain_index(f)];
      for (int f = 0; f < F; ++f) trial.bias[f] += dx[bias_index(f)];
      for (int i = 0; i < n; ++i) trial.vignette.coefficients[i] += dx[coefficient_index(i)];
      for (int p = 0; p < problem.num_points(); ++p) {
        double hdx = 0;
        for (const auto& [ia, va] : coupling[p]) hdx += va * dx[ia];
        trial.radiance[p] -= (g_r[p] + hdx) / h_rr_damped[p];
      }
      const double trial_cost = dx.allFinite() ? Cost(problem, trial, k) : std::numeric_limits<double>::infinity();
      if (trial_cost < cost) {
        const double decrease = (cost - trial_cost) / std::max(cost, 1e-300);
        *state = std::move(trial);
        cost = trial_cost;
        damping = std::max(damping / kDampingShrink, 1e-12);
        accepted = true;
        if (decrease < kConvergedDecrease) return iteration + 1;
      } else {
        damping *= kDampingGrowth;
      }
    }
    if (!accepted) break;  // no step lowers the cost: at a minimum
  }
  return iteration;
}

double Rms(const Problem& problem, const State& s) {
  double sum = 0;
  for (const VignetteObservation& o : problem.obs) sum += Residual(s, o) * Residual(s, o);
  return problem.obs.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(problem.obs.size()));
}

State InitialState(const Problem& problem, int num_coefficients) {
  State s;
  s.gain.assign(problem.num_frames, 1.0);
  s.bias.assign(problem.num_frames, 0.0);
  s.vignette.coefficients.assign(num_coefficients, 0.0);
  s.radiance.resize(problem.num_points());
  for (int p = 0; p < problem.num_points(); ++p) {
    double sum = 0;
    for (int j = problem.point_begin[p]; j < problem.point_begin[p + 1]; ++j) sum += problem.obs[j].intensity;
    s.radiance[p] = sum / (problem.point_begin[p + 1] - problem.point_begin[p]);
  }
  return s;
}

}  // namespace

VignetteFit FitVignette(const std::vector<VignetteObservation>& observations, int num_points, int num_frames,
                        const VignetteFitOptions& options) {
  options.Check();
  Require(num_points >= 1 && num_frames >= 1, "vignette fit: needs at least one point and one frame");
  std::vector<int> count(num_points, 0);
  for (const VignetteObservation& o : observations) {
    Require(o.point >= 0 && o.point < num_points && o.frame >= 0 && o.frame < num_frames,
            "vignette fit: observation index out of range");
    ++count[o.point];
  }
  // Keep the points seen often enough, renumbered, observations grouped by point.
  std::vector<int> new_index(num_points, -1);
  Problem problem;
  problem.num_frames = num_frames;
  problem.point_begin.push_back(0);
  int kept = 0;
  for (int p = 0; p < num_points; ++p) {
    if (count[p] < options.min_observations_per_point) continue;
    new_index[p] = kept++;
    problem.point_begin.push_back(problem.point_begin.back() + count[p]);
  }
  Require(kept > 0, "vignette fit: no point is seen in " + std::to_string(options.min_observations_per_point) +
                        " frames or more");
  problem.obs.resize(problem.point_begin.back());
  std::vector<int> fill(problem.point_begin.begin(), problem.point_begin.end() - 1);
  for (const VignetteObservation& o : observations) {
    if (new_index[o.point] < 0) continue;
    VignetteObservation copy = o;
    copy.point = new_index[o.point];
    problem.obs[fill[copy.point]++] = copy;
  }

  VignetteFit fit;
  fit.points = kept;
  fit.observations = static_cast<int>(problem.obs.size());
  State flat = InitialState(problem, 0);
  Minimise(problem, options, &flat);
  fit.rms_without_vignette = Rms(problem, flat);
  State state = InitialState(problem, options.num_coefficients);
  fit.iterations = Minimise(problem, options, &state);
  fit.rms = Rms(problem, state);
  fit.vignette = state.vignette;
  fit.gain = state.gain;
  fit.bias = state.bias;

  // Profile of the data: (I - b) / (a R) per rho bin.
  std::vector<std::vector<double>> bins;
  for (const VignetteObservation& o : problem.obs) {
    const double denominator = state.gain[o.frame] * state.radiance[o.point];
    if (!(std::abs(denominator) > 1e-9)) continue;
    const size_t bin = static_cast<size_t>(std::sqrt(o.rho_sq) / kVignetteProfileBinWidth);
    if (bin >= bins.size()) bins.resize(bin + 1);
    bins[bin].push_back((o.intensity - state.bias[o.frame]) / denominator);
  }
  for (size_t i = 0; i < bins.size(); ++i) {
    fit.profile_rho.push_back((i + 0.5) * kVignetteProfileBinWidth);
    fit.profile_ratio.push_back(static_cast<int>(bins[i].size()) >= kVignetteProfileMinSamples
                                    ? Median(bins[i])
                                    : std::numeric_limits<double>::quiet_NaN());
  }
  return fit;
}

}  // namespace dvso::vo
