#include "stacknet/latency.h"

#include <algorithm>
#include <chrono>
#include <numeric>

#include "core/error.h"
#include "stacknet/device.h"
#include "stacknet/export.h"

namespace dvso::stacknet {

void LatencyOptions::Check() const {
  Require(dtype == "fp32" || dtype == "fp16" || dtype == "bf16", "bench dtype must be fp32, fp16 or bf16");
  Require(batch >= 1 && height >= 32 && width >= 32 && height % 32 == 0 && width % 32 == 0,
          "bench: batch >= 1 and height/width positive multiples of 32");
  Require(warmup >= 0 && runs >= 1 && max_seconds > 0, "bench: warmup >= 0, runs >= 1, max_seconds > 0");
}

double Percentile(std::vector<double> samples, double percent) {
  Require(!samples.empty(), "Percentile of no samples");
  std::sort(samples.begin(), samples.end());
  const double rank = percent / 100.0 * (samples.size() - 1);
  const size_t lo = static_cast<size_t>(rank);
  const size_t hi = std::min(lo + 1, samples.size() - 1);
  return samples[lo] + (rank - lo) * (samples[hi] - samples[lo]);
}

LatencyStats MeasureLatency(const torch::jit::Module& loaded, const torch::Device& device, const LatencyOptions& options) {
  options.Check();
  const bool cuda = device.is_cuda();
  Require(cuda || options.dtype == "fp32", "fp16/bf16 latency is measured on CUDA only");
  torch::jit::Module module = loaded.deepcopy();
  module.eval();
  const torch::ScalarType type = options.dtype == "fp16"   ? torch::kHalf
                                 : options.dtype == "bf16" ? torch::kBFloat16
                                                           : torch::kFloat32;
  module.to(type);
  UseInferenceLayout(module, device);
  const torch::Tensor input =
      ToConvolutionLayout(torch::rand({options.batch, 3, options.height, options.width}).to(device).to(type), device);
  torch::NoGradGuard no_grad;
  auto run_once = [&] {
    const auto start = std::chrono::steady_clock::now();
    auto out = module.forward({input});
    if (cuda) torch::cuda::synchronize();
    // Touch the result so that nothing lazily pending is left out of the timing.
    (void)out.toTuple()->elements()[0].toTensor().size(0);
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  };
  for (int i = 0; i < options.warmup; ++i) run_once();
  std::vector<double> samples;
  const auto budget_start = std::chrono::steady_clock::now();
  while (static_cast<int>(samples.size()) < options.runs) {
    samples.push_back(run_once());
    const double spent = std::chrono::duration<double>(std::chrono::steady_clock::now() - budget_start).count();
    if (samples.size() >= 3 && spent > options.max_seconds) break;
  }
  LatencyStats stats;
  stats.device = cuda ? "cuda" : "cpu";
  stats.dtype = options.dtype;
  stats.batch = options.batch;
  stats.height = options.height;
  stats.width = options.width;
  stats.threads = cuda ? 0 : at::get_num_threads();
  stats.runs = static_cast<int>(samples.size());
  stats.median_ms = Percentile(samples, 50);
  stats.p90_ms = Percentile(samples, 90);
  stats.mean_ms = std::accumulate(samples.begin(), samples.end(), 0.0) / samples.size();
  stats.min_ms = *std::min_element(samples.begin(), samples.end());
  stats.max_ms = *std::max_element(samples.begin(), samples.end());
  return stats;
}

}  // namespace dvso::stacknet
