// RunDemoDepthNetwork with LibTorch: the committed StackNet model predicts
// disparities for every frame of the demo sequence; they are evaluated against
// the simulator's exact disparity (0-80 m, as the paper's Table 1 upper part).
#include <filesystem>
#include <iostream>
#include <memory>

#include "core/disparity_io.h"
#include "core/eval_depth.h"
#include "core/fs_util.h"
#include "core/progress.h"
#include "core/sequence.h"
#include "pipelines/demo_steps.h"
#include "stacknet/predictor.h"

namespace dvso::cli {

nlohmann::json RunDemoDepthNetwork(const std::string& model_path, const std::string& sequence_dir,
                                   const std::string& out_dir, bool progress) {
  if (!std::filesystem::is_regular_file(model_path)) {
    std::cout << "skipped: no model at " << model_path << "\n";
    return {{"skipped", "no model file"}};
  }
  const auto sequence = OpenSequence(sequence_dir);
  stacknet::TorchDisparityPredictor predictor(model_path);
  const std::string left_dir = JoinPath(out_dir, "left");
  EnsureDirectory(left_dir);
  SequenceReadOptions read;
  read.load_right = false;
  read.load_color = true;
  std::unique_ptr<ProgressBar> bar;
  if (progress) bar = std::make_unique<ProgressBar>("predict", sequence->size());
  for (int i = 0; i < sequence->size(); ++i) {
    const StereoFrame frame = sequence->Read(i, read);
    const DisparityPair pair = predictor.PredictImage(frame.left_color.empty() ? frame.left : frame.left_color);
    WriteKittiMapPng(JoinPath(left_dir, FrameFileName(i, ".png")), pair.left);
    if (bar) bar->Update(i + 1);
  }
  if (bar) bar->Finish();
  DepthEvalOptions options;
  options.fxb = sequence->camera().FxB();
  const DepthEvalResult result = EvaluateDepthFolders(left_dir, JoinPath(sequence_dir, "disp_0"), options);
  std::cout << "model: " << model_path << "\n" << FormatDepthEvalResult(result, options);
  return DepthEvalResultToJson(result, options);
}

}  // namespace dvso::cli
