// Writes a simulated sequence in the KITTI odometry layout, frame by frame:
//   image_0/ image_1/   grey left/right, uint8 PNG %06d.png
//   image_2/ image_3/   colour left/right (only with options.color)
//   depth_0/            left depth, uint16 PNG metres*256 (0 = sky or >= 256 m)
//   disp_0/ disp_1/     left / right GT disparity, uint16 PNG pixels*256 (0 = sky)
//   calib.txt times.txt poses.txt (GT, first frame = identity)
//   exposures.txt       per frame: index, gain, bias (DSO affine brightness)
//   vignette.png        V(x) as uint16 (65535 = 1), when vignetting is on
//   vignette_right.png  the right lens's V(x), when it has its own (--right-vignetting)
//   simulation.yaml     the options and world statistics of the run
// The metadata files of an earlier run in the folder are removed first and this
// run's are written last, so an interrupted run is recognisably incomplete; every
// file is written atomically.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <future>
#include <iomanip>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>
#include <opencv2/imgcodecs.hpp>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/image_file.h"
#include "core/progress.h"
#include "core/sequence.h"
#include "core/simulator.h"
#include "core/trajectory.h"
#include "core/vignette.h"

namespace dvso {
namespace {

void WritePng(const std::string& path, const cv::Mat& image) {
  WriteImageAtomically(path, image, {cv::IMWRITE_PNG_COMPRESSION, 1});
}

void WriteText(const std::string& path, const std::function<void(std::ostream&)>& body) {
  WriteStreamAtomically(path, body);
}

void WriteSimulationYaml(const std::string& path, const StreetSimulator& simulator, const SimulationSummary& summary) {
  const SimulatorOptions& o = simulator.options();
  const sim::Scene& scene = simulator.scene();
  WriteText(path, [&](std::ostream& out) {
    out << std::setprecision(10);
    out << "# dvso simulate: options and world statistics of this run\n";
    out << "world_version: " << o.world_version << "\n";
    out << "trajectory: \"" << (o.trajectory_path.empty() ? "generated" : o.trajectory_path) << "\"\n";
    out << "first_frame: " << o.first_frame << "\nnum_frames: " << summary.frames << "\nstride: " << o.stride << "\n";
    out << "seed: " << o.seed << "\n";
    out << "camera: {width: " << o.camera.left.width << ", height: " << o.camera.left.height
        << ", fx: " << o.camera.left.fx << ", fy: " << o.camera.left.fy << ", cx: " << o.camera.left.cx
        << ", cy: " << o.camera.left.cy << ", baseline: " << o.camera.baseline << "}\n";
    out << "camera_height: " << o.camera_height
        << "\nframe_interval: " << o.frame_interval
        << "\nmax_distance: " << o.max_distance << "\n";
    out << "exposure_drift: " << (o.exposure_drift ? "true" : "false") << "\nexposure_sigma: " << o.exposure_sigma
        << "\nexposure_max: " << o.exposure_max << "\nbias_sigma: " << o.bias_sigma << "\n";
    out << "right_gain: " << o.right_gain << "\nright_bias: " << o.right_bias << "\n";
    out << "vignetting: " << (o.vignetting ? "true" : "false") << "\nvignetting_strength: " << o.vignetting_strength
        << "\nright_vignetting_strength: " << o.right_vignetting_strength << "\n";
    out << "noise: " << (o.noise ? "true" : "false") << "\nnoise_sigma: " << o.noise_sigma << "\n";
    out << "color: " << (o.color ? "true" : "false") << "\nedge_antialiasing: " << (o.edge_antialiasing ? "true" : "false")
        << "\n";
    out << "building_density: " << o.scene.building_density << "\ncar_density: " << o.scene.car_density
        << "\ntree_density: " << o.scene.tree_density << "\nshadows: " << (o.scene.shadows ? "true" : "false") << "\n";
    const sim::Appearance& a = scene.appearance;
    auto vec = [](const Eigen::Vector3f& v) {
      std::ostringstream s;
      s << "[" << v.x() << ", " << v.y() << ", " << v.z() << "]";
      return s.str();
    };
    out << "appearance: {varied: " << (a.varied ? "true" : "false") << ", sun_strength: " << a.sun_strength
        << ", sky_light: " << a.sky_light << ", sky_light_up: " << a.sky_light_up << ", light_colour: "
        << vec(a.light_colour) << ", sky_zenith: " << vec(a.sky_zenith) << ", cloud_threshold: " << a.cloud_threshold
        << ", road_texture: " << (a.road_texture == sim::kTexRoadConcrete ? "concrete" : "asphalt")
        << ", road_tint: " << vec(a.road_tint) << ", grass_tint: " << vec(a.grass_tint)
        << ", leaves_tint: " << vec(a.leaves_tint) << ", facade_styles: " << a.facade_styles
        << ", facade_free_colour: " << a.facade_free_colour << ", car_shapes: " << (a.car_shapes ? "true" : "false")
        << ", car_detail: " << a.car_detail
        << "}\n";
    out << "exposure_level: " << o.exposure_level << "\nheight_jitter: " << o.height_jitter << "\n";
    out << "world: {triangles: " << scene.triangles.size() << ", buildings: " << scene.num_buildings
        << ", cars: " << scene.num_cars << ", poles: " << scene.num_poles << ", trees: " << scene.num_trees << "}\n";
    out << "path_length_m: " << summary.path_length << "\nrender_seconds: " << summary.seconds << "\n";
  });
}

}  // namespace

namespace {

// The files written after every frame, in the order written; together they make the folder a sequence
// that readers accept (calib.txt and times.txt at least).
const std::vector<std::string> kMetadataFiles = {"calib.txt", "times.txt", "poses.txt", "exposures.txt",
                                                 "vignette.png", "vignette_right.png", "simulation.yaml"};

// V(x) = 1 - strength * rho^2 (the renderer's fall-off) as a uint16 PNG (65535 = 1).
void WriteVignettePng(const std::string& path, const PinholeCamera& c, double strength) {
  RadialVignette{{-strength}}.WritePng(path, c);
}

// Removes `path` if it exists; throws dvso::Error naming it when it cannot be removed.
void RemoveEarlierRunFile(const std::string& path) {
  std::error_code error;
  std::filesystem::remove(path, error);
  RequireFile(!error, path, "cannot remove the file of an earlier run: " + error.message());
}

// Removes the simulator's frame files (%06d.png) numbered `first_stale` and up from `dir`, if it exists;
// other files are left alone.
void RemoveStaleSimulatedFrames(const std::string& dir, int first_stale) {
  if (!std::filesystem::is_directory(dir)) return;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string stem = entry.path().stem().string();
    if (entry.path().extension() != ".png" || stem.size() != 6 ||
        !std::all_of(stem.begin(), stem.end(), [](unsigned char c) { return std::isdigit(c) != 0; })) {
      continue;
    }
    if (std::stoi(stem) >= first_stale) std::filesystem::remove(entry.path());
  }
}

}  // namespace

SimulationSummary WriteSimulatedSequence(const SimulatorOptions& options, const std::string& output_dir,
                                         bool show_progress) {
  const auto start = std::chrono::steady_clock::now();
  StreetSimulator simulator(options);
  const int n = simulator.num_frames();
  const std::vector<std::string> grey_dirs = {"image_0", "image_1", "depth_0", "disp_0", "disp_1"};
  const std::vector<std::string> colour_dirs = {"image_2", "image_3"};
  // A rerun into the folder of an earlier run (only now: the options and trajectory were accepted by the
  // simulator above, so a typo leaves the earlier sequence whole):
  //  - its metadata goes first: until this run writes its own at the end, the folder is recognisably
  //    incomplete (no times.txt / calib.txt) instead of old poses and times beside a mix of new and old
  //    frames, should the run be killed or fail on the way;
  //  - temporary files of a killed writer (000123.tmp-writing.png) go too: no rule below matches them.
  if (std::filesystem::is_directory(output_dir)) {
    for (const auto& f : kMetadataFiles) RemoveEarlierRunFile(JoinPath(output_dir, f));
    RemoveUnfinishedAtomicWrites(output_dir);
    for (const auto& d : grey_dirs) RemoveUnfinishedAtomicWrites(JoinPath(output_dir, d));
    for (const auto& d : colour_dirs) RemoveUnfinishedAtomicWrites(JoinPath(output_dir, d));
  }
  for (const auto& d : grey_dirs) EnsureDirectory(JoinPath(output_dir, d));
  if (options.color) {
    for (const auto& d : colour_dirs) EnsureDirectory(JoinPath(output_dir, d));
  }

  SimulationSummary summary;
  Trajectory poses;
  std::unique_ptr<ProgressBar> bar;
  if (show_progress) bar = std::make_unique<ProgressBar>("simulate", n);
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const SimulatedFrame frame = simulator.Render(i);
    const std::string name = FrameFileName(i, ".png");
    // Depth beyond the uint16 range (256 m) and disparities beyond 256 px (near surfaces of large
    // images or long baselines) are marked invalid, not clamped.
    const cv::Mat depth = InvalidBeyondKittiMapRange(frame.left.depth);
    const cv::Mat disparity_left = InvalidBeyondKittiMapRange(frame.disparity_left);
    const cv::Mat disparity_right = InvalidBeyondKittiMapRange(frame.disparity_right);
    // Two writers in parallel: PNG compression is a good part of the time per frame.
    auto second = std::async(std::launch::async, [&]() {
      WritePng(JoinPath(JoinPath(output_dir, "image_1"), name), frame.right.grey);
      WriteKittiMapPng(JoinPath(JoinPath(output_dir, "disp_0"), name), disparity_left);
      if (options.color) WritePng(JoinPath(JoinPath(output_dir, "image_3"), name), frame.right.color);
    });
    WritePng(JoinPath(JoinPath(output_dir, "image_0"), name), frame.left.grey);
    WriteKittiMapPng(JoinPath(JoinPath(output_dir, "depth_0"), name), depth);
    WriteKittiMapPng(JoinPath(JoinPath(output_dir, "disp_1"), name), disparity_right);
    if (options.color) WritePng(JoinPath(JoinPath(output_dir, "image_2"), name), frame.left.color);
    second.get();

    StampedPose pose;
    pose.timestamp = frame.timestamp;
    pose.T_world_camera = frame.T_first_camera;
    poses.poses.push_back(pose);
    if (i > 0) summary.path_length += (frame.T_first_camera.translation() - previous).norm();
    previous = frame.T_first_camera.translation();
    if (bar) {
      char status[64];
      std::snprintf(status, sizeof(status), "%.1f m driven", summary.path_length);
      bar->Update(i + 1, status);
    }
  }
  if (bar) bar->Finish();
  // A longer (or colour) earlier simulation into the same folder leaves frames this one did not write:
  // without this, the folder would hold more images than poses and times.
  for (const auto& d : grey_dirs) RemoveStaleSimulatedFrames(JoinPath(output_dir, d), n);
  for (const auto& d : colour_dirs) RemoveStaleSimulatedFrames(JoinPath(output_dir, d), options.color ? n : 0);
  if (!options.color) {
    // The readers take an image_2/ folder for colour images (sequence_kitti.cpp): an emptied one of an
    // earlier colour run would make `predict` and the raw-layout writer look for image_2/000000.png.
    // remove() takes empty folders only: one that still holds files that are not ours stays.
    for (const auto& d : colour_dirs) {
      std::error_code not_empty;
      std::filesystem::remove(JoinPath(output_dir, d), not_empty);
    }
  }

  // Metadata last.
  WriteKittiCalibration(JoinPath(output_dir, "calib.txt"), simulator.camera());
  WriteText(JoinPath(output_dir, "times.txt"), [&](std::ostream& out) {
    out << std::scientific << std::setprecision(6);
    for (const auto& p : poses.poses) out << p.timestamp << "\n";
  });
  WriteKittiTrajectory(JoinPath(output_dir, "poses.txt"), poses);
  WriteText(JoinPath(output_dir, "exposures.txt"), [&](std::ostream& out) {
    out << "# frame gain bias  (I = gain * 255 * V(x) * radiance + bias + noise)\n" << std::setprecision(9);
    for (int i = 0; i < n; ++i) {
      const sim::Photometric p = simulator.Exposure(i, 0);
      out << i << " " << p.gain << " " << p.bias << "\n";
    }
  });
  if (options.vignetting) {
    WriteVignettePng(JoinPath(output_dir, "vignette.png"), options.camera.left, options.vignetting_strength);
    if (options.right_vignetting_strength >= 0) {
      WriteVignettePng(JoinPath(output_dir, "vignette_right.png"), options.camera.left,
                       options.right_vignetting_strength);
    }
  }
  // (Without vignetting there is no vignette.png: an earlier vignetted run's map, which would make a
  // photometric calibration correct images that have none, went with the other metadata at the start.)
  summary.frames = n;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteSimulationYaml(JoinPath(output_dir, "simulation.yaml"), simulator, summary);
  return summary;
}

}  // namespace dvso
