// `dvso oxts-poses`: ground-truth camera poses of a KITTI raw drive from its
// GPS/IMU packets (core/kitti_oxts.h has the devkit convention), written as a
// KITTI poses file for `dvso eval-odometry`.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <optional>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_oxts.h"
#include "core/sequence.h"
#include "core/trajectory.h"
#include "pipelines/commands.h"

namespace dvso::cli {

namespace {

struct OxtsPosesArgs {
  std::string drive_dir, out_path;
  int camera = 0;
};

void Run(const OxtsPosesArgs& args) {
  // Keyed by file number: packet N is frame N's on a sync drive, and line N of oxts/timestamps.txt is its time.
  const std::map<long long, Eigen::Isometry3d> packets = OxtsCameraPoses(args.drive_dir, args.camera);
  // One line per frame the odometry keeps: the drive opened as a sequence (the pair of the chosen camera)
  // skips left frames without a right partner (extract drives drop frames), so the trajectory and this
  // file match line by line. Frame names are the file numbers.
  // A drive without images (only oxts/ downloaded) gets one line per packet.
  Trajectory trajectory;
  if (!IsKittiRawDrive(args.drive_dir)) {
    // Line k is packet first + k: a missing packet would move every later pose onto another frame's line.
    long long expected = packets.begin()->first;
    for (const auto& [number, pose] : packets) {
      RequireFile(number == expected, OxtsPacketPath(args.drive_dir, expected),
                  "missing OXTS packet (one line per packet: the poses after it would land on other frames' lines)");
      trajectory.poses.push_back({static_cast<double>(number), pose});
      ++expected;
    }
    WriteKittiTrajectory(args.out_path, trajectory);
    std::cout << packets.size() << " poses of rectified camera " << args.camera
              << ", one per OXTS packet (the drive has no image_0X/data to match frames with; path "
              << trajectory.PathLength() << " m) written to " << args.out_path << "\n";
    return;
  }
  const std::unique_ptr<SequenceReader> sequence =
      OpenKittiRawSequence(args.drive_dir, args.camera >= 2 ? CameraPair::kColour : CameraPair::kGrey);
  // Sync drives: packet N is the one the devkit picked for frame N. Extract drives record the GPS/IMU at
  // 100 Hz and number every stream on its own: the packet nearest in time to the frame's image, as the
  // devkit's synchronisation does.
  const bool by_time = IsKittiRawExtractDrive(args.drive_dir);
  std::vector<double> packet_times, image_times;  // packet_times[k]: the k-th packet (by number)'s time
  std::vector<const Eigen::Isometry3d*> timed_packets;
  if (by_time) {
    const std::string oxts_times_path = JoinPath(args.drive_dir, "oxts/timestamps.txt");
    const std::vector<double> lines = ReadKittiRawTimestamps(oxts_times_path);
    for (const auto& [number, pose] : packets) {
      RequireFile(number < static_cast<long long>(lines.size()), oxts_times_path,
                  std::to_string(lines.size()) + " timestamps, none for " + OxtsPacketPath(args.drive_dir, number));
      packet_times.push_back(lines[static_cast<size_t>(number)]);
      timed_packets.push_back(&pose);
    }
    // Frames are named after the pair's LEFT camera (00 or 02): its timestamps, even for --camera 1|3,
    // whose own files are numbered separately once it has dropped a frame.
    const int left_camera = args.camera - args.camera % 2;
    image_times = ReadKittiRawTimestamps(JoinPath(args.drive_dir, "image_0" + std::to_string(left_camera) +
                                                                      "/timestamps.txt"));
  }
  Eigen::Isometry3d first_inverse = Eigen::Isometry3d::Identity();
  int far_packets = 0;
  double worst_gap = 0.0;
  for (int i = 0; i < sequence->size(); ++i) {
    const std::string name = sequence->FrameName(i);
    const std::optional<long long> number = ParseFrameNumber(name);
    RequireFile(number.has_value(), args.drive_dir, "frame " + name + " is not named by its file number");
    Eigen::Isometry3d pose;
    if (by_time) {
      RequireFile(static_cast<size_t>(*number) < image_times.size(), args.drive_dir,
                  "frame " + name + " has no line in its camera's timestamps.txt");
      const double image_time = image_times[static_cast<size_t>(*number)];
      const size_t packet = NearestTimestamp(packet_times, image_time);
      const double gap = std::abs(packet_times[packet] - image_time);
      worst_gap = std::max(worst_gap, gap);
      if (gap > kMaxOxtsFrameGap) ++far_packets;
      pose = *timed_packets[packet];
    } else {
      // An error, not a skipped frame: this file must match the odometry's trajectory line by line.
      const auto packet = packets.find(*number);
      RequireFile(packet != packets.end(), OxtsPacketPath(args.drive_dir, *number),
                  "missing: frame " + name + " has no OXTS packet of its own");
      pose = packet->second;
    }
    if (i == 0) first_inverse = pose.inverse();
    trajectory.poses.push_back({sequence->timestamps()[i], first_inverse * pose});
  }
  if (far_packets > 0) {
    std::cerr << "dvso: warning: " << args.drive_dir << ": " << far_packets << " frame(s) whose nearest OXTS packet is more "
              << "than " << kMaxOxtsFrameGap << " s away (worst " << worst_gap << " s): their poses are less exact\n";
  }
  WriteKittiTrajectory(args.out_path, trajectory);
  std::cout << trajectory.poses.size() << " poses of rectified camera " << args.camera << " (" << packets.size()
            << " OXTS packets, " << (by_time ? "the nearest in time to" : "one per") << " each kept stereo frame; path "
            << trajectory.PathLength() << " m) written to " << args.out_path << "\n";
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
  cmd->add_option("--out", args->out_path, "KITTI poses file, one line per stereo frame the odometry reads from the drive (frames without a "
                  "right image skipped, as there), relative to the first")
      ->required();
  cmd->add_option("--camera", args->camera, "rectified camera: 0 (grey left) or 2 (colour left); 1, 3 right")
      ->capture_default_str();
  cmd->callback([args] { Run(*args); });
}

}  // namespace dvso::cli
