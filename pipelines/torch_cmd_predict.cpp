// `dvso predict --model model.pt (--images DIR | --sequence DIR) --out DIR
// [--post-process] [--device auto|cpu|cuda]`: writes left/%06d.png and
// right/%06d.png (KITTI uint16, disparity * 256, at the input image
// resolution) plus colour-mapped previews in left_color/ and right_color/.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <set>
#include <opencv2/imgcodecs.hpp>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/progress.h"
#include "core/sequence.h"
#include "pipelines/commands.h"
#include "stacknet/predictor.h"

namespace dvso::cli {
namespace {
namespace fs = std::filesystem;

struct PredictArgs {
  std::string model, images, sequence, out;
  stacknet::PredictorOptions options;
  bool no_color = false;
};

void RunPredict(const PredictArgs& args) {
  Require(args.images.empty() != args.sequence.empty(), "give exactly one of --images DIR or --sequence DIR");
  stacknet::TorchDisparityPredictor predictor(args.model, args.options);
  std::cout << "Model " << args.model << " (network input " << predictor.input_width() << "x"
            << predictor.input_height() << ")" << (args.options.post_process ? ", post-processing on" : "") << "\n";
  for (const char* sub : {"left", "right", "left_color", "right_color"}) EnsureDirectory(JoinPath(args.out, sub));
  std::unique_ptr<SequenceReader> sequence;
  std::vector<std::string> files;
  if (!args.sequence.empty()) {
    sequence = OpenSequence(args.sequence);
  } else {
    RequireFile(fs::is_directory(args.images), args.images, "image folder not found");
    for (const auto& entry : fs::directory_iterator(args.images)) {
      const std::string ext = entry.path().extension().string();
      if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") files.push_back(entry.path().string());
    }
    std::sort(files.begin(), files.end());
    RequireFile(!files.empty(), args.images, "no .png/.jpg images");
    std::set<std::string> stems;
    for (const std::string& f : files)
      RequireFile(stems.insert(fs::path(f).stem().string()).second, f,
                  "two images share this name (outputs keep the input names)");
  }
  const int count = sequence ? sequence->size() : static_cast<int>(files.size());
  ProgressBar progress("predict", count);
  for (int i = 0; i < count; ++i) {
    cv::Mat image;
    if (sequence) {
      SequenceReadOptions read;
      read.load_right = false;
      read.load_color = sequence->has_color();
      const StereoFrame frame = sequence->Read(i, read);
      image = frame.left_color.empty() ? frame.left : frame.left_color;
    } else {
      image = cv::imread(files[i], cv::IMREAD_COLOR);
      RequireFile(!image.empty(), files[i], "cannot read image");
    }
    const DisparityPair pair = predictor.PredictImage(image);
    // --images keeps each input's name (as .png); --sequence numbers the frames.
    const std::string name = sequence ? FrameFileName(i, ".png") : fs::path(files[i]).stem().string() + ".png";
    WriteKittiMapPng(JoinPath(JoinPath(args.out, "left"), name), pair.left);
    WriteKittiMapPng(JoinPath(JoinPath(args.out, "right"), name), pair.right);
    if (!args.no_color) {
      cv::imwrite(JoinPath(JoinPath(args.out, "left_color"), name), stacknet::ColorizeDisparity(pair.left));
      cv::imwrite(JoinPath(JoinPath(args.out, "right_color"), name), stacknet::ColorizeDisparity(pair.right));
    }
    progress.Update(i + 1);
  }
  progress.Finish();
  std::cout << "Wrote " << count << " left/right disparity maps to " << args.out << std::endl;
}

}  // namespace

void AddPredictCommand(CLI::App& app) {
  auto args = std::make_shared<PredictArgs>();
  auto* cmd = app.add_subcommand("predict", "Predict left/right disparity maps with an exported model");
  cmd->add_option("--model", args->model, "TorchScript model from `dvso export`")->required()->check(CLI::ExistingFile);
  cmd->add_option("--images", args->images, "Folder of .png/.jpg images; each output keeps its input's name (as .png)");
  cmd->add_option("--sequence", args->sequence, "Sequence folder (KITTI odometry layout / dvso simulate output)");
  cmd->add_option("--out", args->out, "Output folder")->required();
  cmd->add_flag("--post-process", args->options.post_process, "Godard's flip-and-blend post-processing (left)");
  cmd->add_option("--device", args->options.device, "auto, cpu or cuda");
  cmd->add_flag("--no-color", args->no_color, "Skip the colour-mapped previews");
  cmd->callback([args] { RunPredict(*args); });
}

}  // namespace dvso::cli
