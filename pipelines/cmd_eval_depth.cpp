// `dvso eval-depth`: Eigen et al. / monodepth depth metrics of a folder of
// predicted maps against a folder of GT maps (core/eval_depth.h; docs/evaluation.md).
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/eval_depth.h"
#include "core/sequence.h"
#include "pipelines/commands.h"

namespace dvso::cli {

namespace {

struct EvalDepthArgs {
  std::string pred_dir, gt_dir, calib_path, split_path;
  std::string cameras = "grey";  // the pair of --calib whose fx * baseline converts the disparities
  std::string pred_kind = "disparity", gt_kind = "disparity", crop = "none";
  bool json = false;
  DepthEvalOptions options;
};

void Run(EvalDepthArgs& args, const CLI::App& cmd) {
  if (!args.split_path.empty()) {
    // The paper's protocol (section 5.1, Table 1): Velodyne depth GT, Garg crop, 1e-3 .. 80 m.
    if (cmd.count("--gt-kind") == 0) args.gt_kind = "depth";
    if (cmd.count("--crop") == 0) args.crop = "garg";
  }
  Require(args.options.raw_root.empty() || !args.split_path.empty(),
          "--raw-root gives fx * baseline per split line: it needs --split");
  args.options.pred_kind = ParseMapKind(args.pred_kind);
  args.options.gt_kind = ParseMapKind(args.gt_kind);
  args.options.crop = ParseDepthCrop(args.crop);
  // With --split, disparities become depths with each line's own calibration under --raw-root (as monodepth's
  // Eigen evaluation), else with KITTI fx from the GT width times 0.54 m (~1.4 % farther on 2011_09_26); each
  // stays overridable. Depth against depth needs no fx * baseline, nor a KITTI image width.
  if (!args.split_path.empty() && ConvertsDisparity(args.options) && cmd.count("--fxb") == 0 &&
      cmd.count("--calib") == 0 && args.options.raw_root.empty()) {
    args.options.kitti_focal_by_width = true;
  }
  if (!args.calib_path.empty()) {
    Require(args.options.fxb <= 0.0 && !args.options.kitti_focal_by_width,
            "give only one of --fxb, --calib, --kitti-focal and --raw-root");
    // Image size does not enter fx * baseline; KITTI's 1241 x 376 keeps Check() satisfied.
    args.options.fxb = ReadKittiCalibration(args.calib_path, 1241, 376, ParseCameraPair(args.cameras)).FxB();
  }
  args.options.Check();
  if (!args.json) {
    if (!args.split_path.empty()) std::cout << "split        : " << args.split_path << "\n";
    std::cout << "predictions  : " << args.pred_dir << " (" << MapKindName(args.options.pred_kind) << ")\n"
              << "ground truth : " << args.gt_dir << " (" << MapKindName(args.options.gt_kind) << ")\n";
    if (!ConvertsDisparity(args.options)) {
      std::cout << "fx * baseline: not used (depth against depth)\n";
    } else if (args.options.fxb > 0.0) {
      std::cout << "fx * baseline: " << args.options.fxb << " px m"
                << (args.calib_path.empty() ? "" : " (" + args.cameras + " pair of " + args.calib_path + ")") << "\n";
    } else if (args.options.kitti_focal_by_width) {
      std::cout << "fx * baseline: KITTI fx by image width x 0.54 m\n";
    } else if (!args.options.raw_root.empty()) {
      std::cout << "fx * baseline: per split line, from its drive's calib_cam_to_cam.txt under " << args.options.raw_root
                << "\n";
    }
    std::cout << "\n";
  }
  const DepthEvalResult result = args.split_path.empty()
                                     ? EvaluateDepthFolders(args.pred_dir, args.gt_dir, args.options)
                                     : EvaluateDepthSplit(args.split_path, args.pred_dir, args.gt_dir, args.options);
  if (args.json) {
    std::cout << DepthEvalResultToJson(result, args.options).dump(2) << std::endl;
  } else {
    std::cout << FormatDepthEvalResult(result, args.options);
  }
}

}  // namespace

void AddEvalDepthCommand(CLI::App& app) {
  auto args = std::make_shared<EvalDepthArgs>();
  auto* cmd = app.add_subcommand(
      "eval-depth", "Depth metrics (abs rel, sq rel, RMSE, RMSE log, delta < 1.25^k) of predicted vs GT maps");
  cmd->add_option("--pred", args->pred_dir,
                  "folder of predicted KITTI uint16 PNG maps (value / 256); with --split also an .npy stack "
                  "(N, H, W) of disparities / width, one per split line")
      ->required();
  cmd->add_option("--gt,--gt-dir", args->gt_dir, "folder of GT KITTI uint16 PNG maps with the same file names (0 = invalid)")
      ->required();
  cmd->add_option("--pred-kind", args->pred_kind, "predictions hold depth (m) or disparity (px)")
      ->capture_default_str();
  cmd->add_option("--gt-kind", args->gt_kind, "GT holds depth (m) or disparity (px)")->capture_default_str();
  auto* fxb = cmd->add_option("--fxb", args->options.fxb,
                              "focal length (px, GT resolution) * baseline (m) to turn disparity into depth");
  auto* calib = cmd->add_option("--calib", args->calib_path,
                                "KITTI odometry calib.txt giving fx * baseline of the pair --cameras names")
                    ->excludes(fxb);
  cmd->add_option("--cameras", args->cameras,
                  "with --calib: the pair the predictions were made on, grey (P0/P1, default: the pair odometry "
                  "and predict read of an odometry folder) or colour (P2/P3: predict --cameras colour, the "
                  "network's training pair); on KITTI the two pairs' baselines differ by up to ~1 %")
      ->capture_default_str()
      ->check(CLI::IsMember({"grey", "gray", "colour", "color"}))
      ->needs(calib);
  auto* kitti_focal = cmd->add_flag("--kitti-focal", args->options.kitti_focal_by_width,
                "fx from the GT width (KITTI calibration days, as monodepth) times baseline 0.54 m")
      ->excludes(fxb);
  cmd->add_option("--crop", args->crop, "evaluation crop: none, eigen or garg")->capture_default_str();
  cmd->add_option("--min-depth", args->options.min_depth, "GT kept above, predictions clamped to (m)")
      ->capture_default_str();
  cmd->add_option("--max-depth", args->options.max_depth, "GT kept below, predictions clamped to (m)")
      ->capture_default_str();
  cmd->add_flag("--median-scaling", args->options.median_scaling,
                "scale each prediction by median(GT) / median(prediction) (monocular)");
  cmd->add_option("--split", args->split_path,
                  "split file ('<drive> <frame> <side>' lines): GT and predictions are %06d.png in split order "
                  "(gt-depth --split); defaults become the paper's protocol: --gt-kind depth --crop garg, and --kitti-focal "
                  "unless --raw-root, --fxb or --calib gives fx * baseline");
  cmd->add_option("--raw-root", args->options.raw_root,
                  "with --split: KITTI raw root; each line's disparities become depths with its drive's calibration "
                  "(fx of camera 02/03 x colour baseline b3 - b2, monodepth's Eigen-split conversion)")
      ->excludes(fxb)
      ->excludes(calib)
      ->excludes(kitti_focal);
  cmd->add_option("--ranges", args->options.range_edges,
                  "also break the errors down by GT depth range, pixels pooled over images, with the signed "
                  "median pred/GT depth per range: increasing edges in m, e.g. 0,5,10,20,40,80")
      ->delimiter(',');
  cmd->add_option("--images", args->options.image_dir,
                  "with --ranges and --min-gradient: folder of the images, named like the GT maps, whose gradient "
                  "selects the breakdown's pixels");
  cmd->add_option("--min-gradient", args->options.min_image_gradient,
                  "with --images: the breakdown counts only pixels with a Sobel gradient magnitude >= this (grey "
                  "levels), where DSO selects points: DVSO's scale follows the median pred/GT there")
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "print exactly one JSON object on stdout");
  cmd->callback([args, cmd] { Run(*args, *cmd); });
}

}  // namespace dvso::cli
