// `dvso gt-depth`: sparse depth ground truth of a KITTI raw drive, its Velodyne
// scans projected into a rectified camera (core/kitti_velodyne.h), one KITTI
// depth PNG (m * 256, 0 = none) per scan, named like the scan; each pixel holds
// the Velodyne x of its point (monodepth's Eigen-split GT) or its camera z.
#include <algorithm>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>

#include "core/depth_split.h"
#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_raw_calibration.h"
#include "core/kitti_velodyne.h"
#include "core/progress.h"
#include "pipelines/commands.h"

namespace dvso::cli {

namespace {

namespace fs = std::filesystem;

struct GtDepthArgs {
  std::string drive_dir, out_dir, split_path, raw_root;
  std::string depth_value = "velodyne-x";
  int camera = 2;
  bool quiet = false;
};

// The scan of a drive's frame: .bin (sync) or .txt (extract).
std::string ScanPath(const std::string& drive_dir, const std::string& frame_name) {
  const fs::path dir = fs::path(drive_dir) / "velodyne_points" / "data";
  const fs::path bin = dir / (frame_name + ".bin");
  if (fs::exists(bin)) return bin.string();
  const fs::path txt = dir / (frame_name + ".txt");
  RequireFile(fs::exists(txt), bin.string(), "no Velodyne scan (.bin or .txt) for this split entry");
  return txt.string();
}

// One GT map per split line, %06d.png in split order, each in its line's camera (l = 02, r = 03).
void RunSplit(const GtDepthArgs& args) {
  Require(!args.raw_root.empty(), "--split needs --raw-root (the folder holding the date folders)");
  const VelodyneDepthValue value = ParseVelodyneDepthValue(args.depth_value);
  const std::vector<SplitEntry> entries = ReadSplitFile(args.split_path);
  EnsureDirectory(args.out_dir);
  std::map<std::pair<std::string, int>, VelodyneProjection> projections;  // per (drive, camera)
  ProgressBar progress("gt-depth", static_cast<long>(entries.size()));
  long points = 0;
  for (size_t i = 0; i < entries.size(); ++i) {
    const SplitEntry& entry = entries[i];
    const std::string drive_dir = JoinPath(args.raw_root, entry.drive);
    RequireFile(fs::is_directory(drive_dir), drive_dir,
                "drive of split line " + std::to_string(i + 1) + " not found under --raw-root");
    const auto key = std::make_pair(drive_dir, entry.Camera());
    if (!projections.count(key)) {
      projections[key] = ReadVelodyneProjection(FindRawCalibrationDir(drive_dir), entry.Camera());
    }
    const cv::Mat depth =
        ProjectVelodyneDepth(ReadVelodyneScan(ScanPath(drive_dir, entry.FrameName())), projections[key], value);
    points += cv::countNonZero(depth);
    WriteKittiMapPng(JoinPath(args.out_dir, SplitMapName(static_cast<int>(i))), depth);
    if (!args.quiet) progress.Update(static_cast<long>(i + 1));
  }
  if (!args.quiet) progress.Finish();
  std::cout << entries.size() << " depth maps (" << args.depth_value << ") in split order ("
            << points / static_cast<long>(entries.size()) << " points/frame) in " << args.out_dir << "\n";
}

void Run(const GtDepthArgs& args) {
  Require(args.drive_dir.empty() != args.split_path.empty(), "give exactly one of --sequence DRIVE or --split FILE");
  if (!args.split_path.empty()) return RunSplit(args);
  const VelodyneDepthValue value = ParseVelodyneDepthValue(args.depth_value);
  const fs::path scans_dir = fs::path(args.drive_dir) / "velodyne_points" / "data";
  RequireFile(fs::is_directory(scans_dir), scans_dir.string(),
              "no Velodyne folder (KITTI raw layout: DRIVE/velodyne_points/data/*.bin)");
  std::vector<fs::path> scans;
  for (const auto& entry : fs::directory_iterator(scans_dir)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".bin" || ext == ".txt")) scans.push_back(entry.path());
  }
  std::sort(scans.begin(), scans.end());
  RequireFile(!scans.empty(), scans_dir.string(), "no .bin or .txt scans");
  const VelodyneProjection projection = ReadVelodyneProjection(FindRawCalibrationDir(args.drive_dir), args.camera);
  EnsureDirectory(args.out_dir);
  ProgressBar progress("gt-depth", static_cast<long>(scans.size()));
  long points = 0;
  for (size_t i = 0; i < scans.size(); ++i) {
    const cv::Mat depth = ProjectVelodyneDepth(ReadVelodyneScan(scans[i].string()), projection, value);
    points += cv::countNonZero(depth);
    WriteKittiMapPng(JoinPath(args.out_dir, scans[i].stem().string() + ".png"), depth);
    if (!args.quiet) progress.Update(static_cast<long>(i + 1));
  }
  if (!args.quiet) progress.Finish();
  std::cout << scans.size() << " depth maps (" << projection.width << "x" << projection.height << ", camera "
            << args.camera << ", " << args.depth_value << ", " << points / static_cast<long>(scans.size())
            << " points/frame) in " << args.out_dir << "\n";
}

}  // namespace

void AddGtDepthCommand(CLI::App& app) {
  auto args = std::make_shared<GtDepthArgs>();
  auto* cmd = app.add_subcommand(
      "gt-depth",
      "KITTI raw drive: Velodyne scans projected into a rectified camera (nearest point per pixel, points behind "
      "dropped) as KITTI depth PNGs (m * 256), the Eigen-split depth GT of monodepth's generate_depth_map "
      "(0-based pixels: monodepth's maps are shifted by one pixel left and up)");
  auto* sequence = cmd->add_option("--sequence", args->drive_dir,
                                   "drive folder with velodyne_points/data/*.bin (sync) or *.txt (extract)");
  auto* split = cmd->add_option("--split", args->split_path,
                  "instead of --sequence: the frames of a split file ('<drive> <frame> <side>'), written as %06d.png "
                  "in split order, side l in camera 2, r in camera 3 (for eval-depth --split)");
  // Options of the other mode are errors, not silently ignored: each split line names its camera.
  cmd->add_option("--raw-root", args->raw_root, "with --split: the folder holding the date folders")
      ->needs(split)
      ->excludes(sequence);
  cmd->add_option("--out", args->out_dir, "output folder (one PNG per scan, named like it)")->required();
  cmd->add_option("--camera", args->camera,
                  "with --sequence: rectified camera 2 (colour left, the network's) or 0 (grey left); a split "
                  "line's side picks it with --split")
      ->capture_default_str()
      ->excludes(split);
  cmd->add_option("--depth-value", args->depth_value,
                  "what a pixel holds: velodyne-x (default), the point's forward distance from the Velodyne, as "
                  "monodepth's and monodepth2's Eigen-split GT (generate_depth_map(..., vel_depth=True)), which "
                  "published abs-rel numbers use; or camera-z, its depth along the rectified camera's axis (on "
                  "KITTI ~0.27 m less: the Velodyne sits behind the cameras)")
      ->capture_default_str()
      ->check(CLI::IsMember({"velodyne-x", "camera-z"}));
  cmd->add_flag("--quiet", args->quiet, "no progress bar");
  cmd->callback([args] { Run(*args); });
}

}  // namespace dvso::cli
