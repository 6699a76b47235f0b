// Speed of the windowed photometric bundle adjustment (vo/optimization) at
// KITTI resolution: 7 keyframes of 1241x376, ~2000 active points, each with
// temporal residuals to the 6 other keyframes (+ static stereo with --stereo).
// Reports ms per linearisation pass, per energy pass, per reduce+solve, and
// per Optimize() iteration.
//   build-*/benchmarks/bench_backend_optimizer [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include "tests/vo/test_backend_util.h"
#include "vo/optimization/accumulator.h"
#include "vo/optimization/marginalization.h"
#include "vo/optimization/schur_solver.h"

namespace dvso::vo {
namespace {

const testing::SceneWindow& Scene(bool stereo) {
  static std::unique_ptr<testing::SceneWindow> mono, with_stereo;
  std::unique_ptr<testing::SceneWindow>& slot = stereo ? with_stereo : mono;
  if (!slot) {
    WindowOptions options;
    testing::SceneWindowSpec spec;
    spec.width = 1241;
    spec.height = 376;
    spec.num_keyframes = 7;
    spec.num_hosts = 6;
    spec.grid_step = 17;  // ~2000 points over 6 hosts
    spec.stereo = stereo;
    spec.pose_noise_t = 0.01;
    spec.pose_noise_r = 0.002;
    spec.idepth_noise = 0.05;
    slot = std::make_unique<testing::SceneWindow>(testing::BuildSceneWindow(options, spec));
    fprintf(stderr, "scene (%s): %d keyframes, %d points\n", stereo ? "stereo" : "mono",
            slot->window->num_keyframes(), slot->window->num_points());
  }
  return *slot;
}

Window CopyWindow(bool stereo, int threads) {
  Window w = *Scene(stereo).window;
  WindowOptions o = w.options();
  o.num_threads = threads;
  w.SetOptions(o);
  return w;
}

void BM_Linearize(benchmark::State& state) {
  Window w = CopyWindow(state.range(0), state.range(1));
  std::vector<Keyframe>& kfs = w.mutable_keyframes();
  const std::vector<PointRef> refs = CollectPoints(kfs);
  int residuals = 0;
  for (auto _ : state) {
    WindowLinearizer lin(&kfs, w.camera(), w.options());
    lin.Linearize(refs);
    residuals = lin.num_active_residuals();
  }
  state.counters["points"] = refs.size();
  state.counters["active_residuals"] = residuals;
}

void BM_Energy(benchmark::State& state) {
  Window w = CopyWindow(state.range(0), state.range(1));
  for (auto _ : state) {
    benchmark::DoNotOptimize(EvaluateWindowEnergy(&w.mutable_keyframes(), w.camera(), w.options(), false).active);
  }
}

void BM_ReduceAndSolve(benchmark::State& state) {
  Window w = CopyWindow(state.range(0), 1);
  std::vector<Keyframe>& kfs = w.mutable_keyframes();
  WindowLinearizer lin(&kfs, w.camera(), w.options());
  lin.Linearize(CollectPoints(kfs));
  const FramePriorTerms priors = EvaluateFramePriors(kfs, w.prior_hessian(), w.prior_gradient());
  for (auto _ : state) {
    WindowStep step;
    benchmark::DoNotOptimize(SolveWindowStep(lin, 1e-4, priors.H, priors.b, &step));
  }
}

// Optimize(6) from the perturbed start; reports ms per LM iteration.
void BM_Optimize(benchmark::State& state) {
  double total_ms = 0.0;
  int iterations = 0;
  for (auto _ : state) {
    state.PauseTiming();
    Window w = CopyWindow(state.range(0), state.range(1));
    state.ResumeTiming();
    const OptimizationSummary s = w.Optimize(6);
    total_ms += s.total_ms;
    iterations += s.iterations;
  }
  state.counters["ms_per_iteration"] = total_ms / std::max(1, iterations);
  state.counters["iterations_per_call"] = static_cast<double>(iterations) / state.iterations();
}

// Args: {stereo, threads}
BENCHMARK(BM_Linearize)->Args({0, 1})->Args({0, 2})->Args({1, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Energy)->Args({0, 1})->Args({1, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ReduceAndSolve)->Args({0, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Optimize)->Args({0, 1})->Args({0, 2})->Args({1, 1})->Args({1, 2})->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace dvso::vo

BENCHMARK_MAIN();
