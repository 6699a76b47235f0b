// Steps of `dvso demo` that need optional components.
#pragma once

#include <nlohmann/json.hpp>
#include <string>

namespace dvso::cli {

// Predicts disparities with the TorchScript model for every frame of the
// sequence, evaluates them against disp_0/ (eval-depth, 0-80 m) and returns the
// metrics. Without LibTorch or without the model file it says so and returns
// {"skipped": reason}.
nlohmann::json RunDemoDepthNetwork(const std::string& model_path, const std::string& sequence_dir,
                                   const std::string& out_dir, bool progress);

}  // namespace dvso::cli
