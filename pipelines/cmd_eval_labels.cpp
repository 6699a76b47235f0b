// `dvso eval-labels`: accuracy of a folder of sparse disparity labels (any
// source: `dvso labels`, another tool) against GT disparity maps, overall and
// by the kind of place each label sits (sdso_labels/label_error_kinds.h).
#include <filesystem>
#include <iostream>
#include <memory>
#include <opencv2/imgcodecs.hpp>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/image_file.h"
#include "pipelines/commands.h"
#include "sdso_labels/label_error_kinds.h"
#include "sdso_labels/label_stats.h"

namespace dvso::cli {

namespace {

namespace fs = std::filesystem;

struct EvalLabelsArgs {
  std::string labels_dir, gt_dir, images_dir, pictures_dir;
  bool json = false;
  labels::LabelErrorKindOptions kinds;
};

void Run(const EvalLabelsArgs& args) {
  args.kinds.Check();
  RequireFile(fs::is_directory(args.labels_dir), args.labels_dir, "not a folder");
  RequireFile(fs::is_directory(args.gt_dir), args.gt_dir, "not a folder");
  if (!args.images_dir.empty()) RequireFile(fs::is_directory(args.images_dir), args.images_dir, "not a folder");
  Require(args.pictures_dir.empty() || !args.images_dir.empty(), "--pictures needs --images (the pictures draw on them)");
  if (!args.pictures_dir.empty() && fs::exists(args.pictures_dir)) {
    for (const std::string& input : {args.labels_dir, args.gt_dir, args.images_dir}) {
      Require(!fs::equivalent(args.pictures_dir, input), "--pictures must not be an input folder: " + input);
    }
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(args.labels_dir))
    if (entry.path().extension() == ".png" && !IsUnfinishedAtomicWrite(entry.path())) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  RequireFile(!files.empty(), args.labels_dir, "no .png label maps");
  if (!args.pictures_dir.empty()) fs::create_directories(args.pictures_dir);
  labels::LabelStatistics statistics;
  labels::LabelErrorBreakdown breakdown(args.kinds);
  for (const auto& file : files) {
    const fs::path gt_path = fs::path(args.gt_dir) / file.filename();
    RequireFile(fs::exists(gt_path), gt_path.string(), "no GT map for label map " + file.string());
    const cv::Mat label_map = ReadKittiMapPng(file.string());
    const cv::Mat gt = ReadKittiMapPng(gt_path.string());
    RequireFile(gt.size() == label_map.size(), gt_path.string(), "size differs from " + file.string());
    cv::Mat image;
    if (!args.images_dir.empty()) {
      const fs::path image_path = fs::path(args.images_dir) / file.filename();
      RequireFile(fs::exists(image_path), image_path.string(), "no image for label map " + file.string());
      image = cv::imread(image_path.string(), cv::IMREAD_GRAYSCALE);
      RequireFile(!image.empty(), image_path.string(), "cannot read image");
      RequireFile(image.size() == label_map.size(), image_path.string(), "size differs from " + file.string());
    }
    if (!args.pictures_dir.empty()) {
      const std::string picture = (fs::path(args.pictures_dir) / file.filename()).string();
      WriteImageAtomically(picture, labels::RenderLabelErrors(label_map, gt, image, args.kinds.wrong_threshold));
    }
    statistics.AddFrame(label_map, gt);
    breakdown.AddFrame(label_map, gt, image);
  }
  if (args.json) {
    nlohmann::json j = statistics.ToJson();
    j["by_kind"] = breakdown.ToJson();
    std::cout << j.dump(2) << std::endl;
    return;
  }
  std::cout << "labels: " << args.labels_dir << "\nGT:     " << args.gt_dir << "\n"
            << statistics.ToText() << "by place (kinds: sdso_labels/label_error_kinds.h"
            << (args.images_dir.empty() ? "; no --images, so no low_texture" : "") << "):\n"
            << breakdown.ToText();
}

}  // namespace

void AddEvalLabelsCommand(CLI::App& app) {
  auto args = std::make_shared<EvalLabelsArgs>();
  auto* cmd = app.add_subcommand("eval-labels",
                                 "Accuracy of sparse disparity labels vs GT maps, by place (edges, thin, far, ...)");
  cmd->add_option("--labels", args->labels_dir, "folder of label maps (KITTI uint16 PNG, value / 256, 0 = none)")
      ->required();
  cmd->add_option("--gt", args->gt_dir, "folder of GT disparity maps with the same file names")->required();
  cmd->add_option("--images", args->images_dir, "folder of the left images with the same names (low-texture kind)");
  cmd->add_option("--pictures", args->pictures_dir,
                  "write one PNG per frame into this folder: the image with right labels green, wrong ones red "
                  "(needs --images)");
  cmd->add_option("--wrong-threshold", args->kinds.wrong_threshold, "px: a label farther from the GT is wrong")
      ->capture_default_str();
  cmd->add_option("--far-fraction", args->kinds.far_fraction, "far = GT disparity below this fraction of the width")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "print exactly one JSON object on stdout");
  cmd->callback([args] { Run(*args); });
}

}  // namespace dvso::cli
