// `dvso oxts-poses`: ground-truth camera poses of a KITTI raw drive from its
// GPS/IMU packets (core/kitti_oxts.h has the devkit convention), written as a
// KITTI poses file for `dvso eval-odometry`.
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/kitti_oxts.h"
#include "core/trajectory.h"
#include "pipelines/commands.h"

namespace dvso::cli {

namespace {

struct OxtsPosesArgs {
  std::string drive_dir, out_path;
  int camera = 0;
};

void Run(const OxtsPosesArgs& args) {
  const std::vector<Eigen::Isometry3d> poses = OxtsCameraPoses(args.drive_dir, args.camera);
  Trajectory trajectory;
  for (size_t i = 0; i < poses.size(); ++i) trajectory.poses.push_back({static_cast<double>(i), poses[i]});
  WriteKittiTrajectory(args.out_path, trajectory);
  std::cout << poses.size() << " poses of rectified camera " << args.camera << " (path " << trajectory.PathLength()
            << " m) written to " << args.out_path << "\n";
}

}  // namespace

void AddOxtsPosesCommand(CLI::App& app) {
  auto args = std::make_shared<OxtsPosesArgs>();
  auto* cmd = app.add_subcommand(
      "oxts-poses",
      "KITTI raw drive: GT camera poses from the GPS/IMU (OXTS) packets, devkit convention (Mercator scale of the "
      "first latitude), moved into the rectified camera through calib_imu_to_velo / calib_velo_to_cam / "
      "calib_cam_to_cam. Caveat: GPS/IMU poses are approximate (cm to dm, more where GPS is poor): good for "
      "t_rel over 100-800 m segments, not for sub-cm checks");
  cmd->add_option("--sequence", args->drive_dir, "drive folder (2011_09_26_drive_NNNN_sync or _extract) with oxts/")
      ->required();
  cmd->add_option("--out", args->out_path, "KITTI poses file, one line per OXTS packet, relative to the first")
      ->required();
  cmd->add_option("--camera", args->camera, "rectified camera: 0 (grey left) or 2 (colour left); 1, 3 right")
      ->capture_default_str();
  cmd->callback([args] { Run(*args); });
}

}  // namespace dvso::cli
