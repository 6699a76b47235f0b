// `dvso bench --model model.pt [--device cpu|cuda] [--height H --width W]
// [--batch 1] [--dtype fp32|fp16|bf16|all] [--json]`: inference latency, by
// default at the input size the model was trained for (its metadata).
#include <iomanip>
#include <iostream>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "pipelines/commands.h"
#include "stacknet/device.h"
#include "stacknet/export.h"
#include "stacknet/latency.h"

namespace dvso::cli {

void AddBenchCommand(CLI::App& app) {
  struct Args {
    std::string model;
    std::string dtype = "all";
    stacknet::LatencyOptions options;
    bool json = false;
  };
  auto args = std::make_shared<Args>();
  args->options.height = args->options.width = 0;  // 0 = the model's input size
  auto* cmd = app.add_subcommand("bench", "Inference latency of a TorchScript model (median / p90)");
  cmd->add_option("--model", args->model, "TorchScript model from `dvso export`")->required()->check(CLI::ExistingFile);
  cmd->add_option("--device", args->options.device, "auto, cpu or cuda");
  cmd->add_option("--height", args->options.height, "Input height (default: the model's input size)");
  cmd->add_option("--width", args->options.width, "Input width (default: the model's input size)");
  cmd->add_option("--batch", args->options.batch, "Batch size");
  cmd->add_option("--dtype", args->dtype, "fp32, fp16, bf16 or all (= fp32, plus fp16 and bf16 on CUDA)");
  cmd->add_option("--warmup", args->options.warmup, "Untimed warm-up runs");
  cmd->add_option("--runs", args->options.runs, "Timed runs (at most)");
  cmd->add_option("--max-seconds", args->options.max_seconds, "Time budget for the timed runs per dtype");
  cmd->add_option("--threads", args->options.num_threads, "CPU threads (0 = hardware cores)");
  cmd->add_flag("--json", args->json, "Print one JSON object");
  cmd->callback([args] {
    const torch::Device device = stacknet::SelectDevice(args->options.device, args->options.num_threads);
    const stacknet::LoadedModel loaded = stacknet::LoadModel(args->model, device);  // once, for every dtype
    if (args->options.height <= 0 || args->options.width <= 0) {
      // What the model sees in `predict` and DVSO; files without the size: LatencyOptions' default (the paper's).
      const ModelMetadata& metadata = loaded.metadata;
      const bool known = metadata.input_width > 0 && metadata.input_height > 0;
      const stacknet::LatencyOptions fallback;
      if (args->options.width <= 0) args->options.width = known ? metadata.input_width : fallback.width;
      if (args->options.height <= 0) args->options.height = known ? metadata.input_height : fallback.height;
    }
    std::vector<std::string> dtypes{args->dtype};
    if (args->dtype == "all") dtypes = device.is_cuda() ? std::vector<std::string>{"fp32", "fp16", "bf16"}
                                                         : std::vector<std::string>{"fp32"};
    nlohmann::json results = nlohmann::json::array();
    for (const auto& dtype : dtypes) {
      stacknet::LatencyOptions options = args->options;
      options.dtype = dtype;
      const stacknet::LatencyStats s = stacknet::MeasureLatency(loaded.module, device, options);
      results.push_back({{"model", args->model}, {"device", s.device}, {"dtype", s.dtype}, {"batch", s.batch},
                         {"height", s.height}, {"width", s.width}, {"threads", s.threads}, {"runs", s.runs},
                         {"median_ms", s.median_ms}, {"p90_ms", s.p90_ms}, {"mean_ms", s.mean_ms},
                         {"min_ms", s.min_ms}, {"max_ms", s.max_ms}});
      if (!args->json) {
        std::cout << std::fixed << std::setprecision(2) << s.device << " " << s.dtype << " batch " << s.batch << " "
                  << s.width << "x" << s.height << (s.device == "cpu" ? " threads " + std::to_string(s.threads) : "")
                  << ": median " << s.median_ms << " ms, p90 " << s.p90_ms << " ms (" << s.runs << " runs, min "
                  << s.min_ms << ", max " << s.max_ms << ")" << std::endl;
      }
    }
    if (args->json) std::cout << (results.size() == 1 ? results[0] : nlohmann::json{{"results", results}}).dump(2) << std::endl;
  });
}

}  // namespace dvso::cli
