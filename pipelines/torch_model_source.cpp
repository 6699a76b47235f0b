// OpenModelDisparitySource for builds with LibTorch: the TorchScript predictor.
#include "pipelines/prediction_source.h"
#include "stacknet/export.h"
#include "stacknet/predictor.h"

namespace dvso::cli {

std::unique_ptr<DisparitySource> OpenModelDisparitySource(const std::string& path, int threads,
                                                          ModelMetadata* metadata) {
  stacknet::PredictorOptions options;
  options.device = "auto";
  options.num_threads = threads;
  auto predictor = std::make_unique<stacknet::TorchDisparityPredictor>(path, options);
  if (metadata != nullptr) *metadata = predictor->metadata();
  return predictor;
}

void WriteModelWithTunedBaseline(const std::string& in_path, const std::string& out_path, const ModelMetadata& metadata) {
  stacknet::WriteModelWithMetadata(in_path, out_path, metadata);
}

}  // namespace dvso::cli
