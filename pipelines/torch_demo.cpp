// RunDemoDepthNetwork with LibTorch: StackNet predictions on the demo sequence.
#include <filesystem>
#include <iostream>

#include "pipelines/demo_steps.h"

namespace dvso::cli {

nlohmann::json RunDemoDepthNetwork(const std::string& model_path, const std::string& sequence_dir,
                                   const std::string& out_dir, bool progress) {
  if (!std::filesystem::is_regular_file(model_path)) {
    std::cout << "skipped: no model at " << model_path << "\n";
    return {{"skipped", "no model file"}};
  }
  // Wired to stacknet's predictor once it lands.
  std::cout << "skipped: depth-network step not wired yet\n";
  return {{"skipped", "not wired yet"}};
}

}  // namespace dvso::cli
