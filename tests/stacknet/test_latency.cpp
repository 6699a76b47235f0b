// `dvso bench`'s measurement: the percentile formula and MeasureLatency on a
// tiny traced network (one loaded module serves every measurement unchanged).
#include <gtest/gtest.h>

#include "core/error.h"
#include "stacknet/export.h"
#include "stacknet/latency.h"
#include "stacknet_test_util.h"

namespace dvso::stacknet {
namespace {

TEST(Latency, PercentileInterpolatesBetweenOrderStatistics) {
  // Sorted: 1 2 4 8; rank = p/100 * 3.
  const std::vector<double> samples{8, 1, 4, 2};
  EXPECT_DOUBLE_EQ(Percentile(samples, 0), 1);
  EXPECT_DOUBLE_EQ(Percentile(samples, 100), 8);
  EXPECT_DOUBLE_EQ(Percentile(samples, 50), 3);    // rank 1.5: halfway between 2 and 4
  EXPECT_DOUBLE_EQ(Percentile(samples, 90), 6.8);  // rank 2.7: 4 + 0.7 * (8 - 4)
  EXPECT_DOUBLE_EQ(Percentile({5}, 90), 5);
  EXPECT_THROW(Percentile({}, 50), Error);
}

TEST(Latency, MeasuresACopyAndLeavesTheCallersModuleAsItWas) {
  torch::manual_seed(3);
  StackNet net(testing::TinyNetwork());
  net->eval();
  const torch::jit::Module module = TraceStackNet(net, /*use_residual=*/true, 32, 64);
  const torch::Device cpu(torch::kCPU);
  LatencyOptions options;
  options.height = 64;
  options.width = 96;
  options.warmup = 1;
  options.runs = 4;
  options.num_threads = 1;
  const LatencyStats stats = MeasureLatency(module, cpu, options);
  EXPECT_EQ(stats.device, "cpu");
  EXPECT_EQ(stats.runs, 4);
  EXPECT_EQ(stats.width, 96);
  EXPECT_EQ(stats.height, 64);
  EXPECT_GT(stats.min_ms, 0);
  EXPECT_LE(stats.min_ms, stats.median_ms);
  EXPECT_LE(stats.median_ms, stats.p90_ms);
  EXPECT_LE(stats.p90_ms, stats.max_ms);
  // The timed copy ran channels-last (UseInferenceLayout); the caller's weights are untouched.
  for (const torch::Tensor& parameter : module.parameters()) {
    if (parameter.dim() == 4) {
      EXPECT_TRUE(parameter.is_contiguous()) << "caller's module was modified";
    }
  }
  options.dtype = "fp16";
  EXPECT_THROW(MeasureLatency(module, cpu, options), Error);  // half types only on CUDA
}

}  // namespace
}  // namespace dvso::stacknet
