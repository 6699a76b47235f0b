// Inference latency of a TorchScript model (`dvso bench`): warm-up runs, then
// timed runs (model loading excluded; CUDA synchronised before reading the
// clock), median and 90th percentile.
#pragma once

#include <torch/script.h>

#include <string>
#include <vector>

namespace dvso::stacknet {

struct LatencyOptions {
  std::string device = "auto";  // auto | cpu | cuda
  std::string dtype = "fp32";   // fp32 | fp16 | bf16 (half types on CUDA only)
  int batch = 1;                // images per forward
  int height = 256;             // input size (paper: 512x256)
  int width = 512;
  int warmup = 3;               // untimed runs
  int runs = 30;                // timed runs (at most)
  double max_seconds = 120;     // stop timing earlier when this budget is spent (>= 3 runs)
  int num_threads = 0;          // CPU threads; 0 = hardware cores
  void Check() const;
};

struct LatencyStats {
  std::string device, dtype;
  int batch = 1, height = 0, width = 0, threads = 0;
  int runs = 0;
  double median_ms = 0, p90_ms = 0, mean_ms = 0, min_ms = 0, max_ms = 0;
};

// Percentile (0..100) of samples by linear interpolation between order statistics.
double Percentile(std::vector<double> samples, double percent);

// Times `module`, loaded on `device` (SelectDevice with options.device and
// options.num_threads): a deep copy is converted to options.dtype, so one loaded
// module serves every dtype and the caller's module is left as it was.
LatencyStats MeasureLatency(const torch::jit::Module& module, const torch::Device& device, const LatencyOptions& options);

}  // namespace dvso::stacknet
