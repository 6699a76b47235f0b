// `dvso simulate`: renders a synthetic KITTI-like stereo sequence with exact
// ground truth (core/simulator.h; docs/simulator.md).
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>

#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_raw_writer.h"
#include "core/sequence.h"
#include "core/simulator.h"
#include "core/simulator_scene.h"
#include "pipelines/commands.h"

namespace dvso::cli {

namespace {

// Options whose presence on the command line Run checks (CLI11 count()): each of them is an error where
// another option would silently override or ignore it.
const char* const kCheckedOptions[] = {"--exposure-level", "--height-jitter", "--noise-sigma",
                                       "--vignetting",     "--right-vignetting", "--exposure-sigma",
                                       "--speed",          "--raw-drive"};

struct SimulateArgs {
  std::string output_dir;
  int width = 0, height = 0;  // 0 = KITTI size
  double fx = 0, fy = 0, cx = -1, cy = -1, baseline = 0;  // 0 / -1 = KITTI (scaled with the size)
  bool no_exposure = false, no_vignetting = false, no_noise = false, no_shadows = false, no_edge_aa = false,
       quiet = false;
  std::string appearance = "fixed";  // fixed | varied
  std::string raw_layout = "none";   // none | sync | extract
  std::string raw_out;               // root of the raw date folder (default OUT/kitti_raw)
  int raw_drop_every = 0;            // extract: the right cameras lose every n-th frame
  std::set<std::string> given;       // the options of kCheckedOptions given on the command line
  SimulatorOptions options;
  KittiRawDriveOptions raw;
};

void Run(SimulateArgs& args) {
  SimulatorOptions& o = args.options;
  const PinholeCamera kitti;
  if (args.width > 0 || args.height > 0) {
    Require(args.width > 0 && args.height > 0, "give both --width and --height");
    o.camera = StereoCamera{kitti, o.camera.baseline}.Resized(args.width, args.height);
  }
  if (args.fx > 0) o.camera.left.fx = args.fx;
  if (args.fy > 0) o.camera.left.fy = args.fy;
  if (args.cx >= 0) o.camera.left.cx = args.cx;
  if (args.cy >= 0) o.camera.left.cy = args.cy;
  if (args.baseline > 0) o.camera.baseline = args.baseline;
  o.exposure_drift = !args.no_exposure;
  o.vignetting = !args.no_vignetting;
  o.noise = !args.no_noise;
  o.scene.shadows = !args.no_shadows;
  o.edge_antialiasing = !args.no_edge_aa;
  o.vary_appearance = args.appearance == "varied";
  const auto given = [&](const char* option) { return args.given.count(option) > 0; };
  // The varied look draws the exposure from the seed (a given level would be silently replaced) and raises
  // the height jitter to at least kVariedHeightJitter (a smaller given one would be); a given camera height
  // stays the centre of the look's +-kVariedCameraHeightRange.
  Require(!(o.vary_appearance && given("--exposure-level")),
          "--exposure-level acts with --appearance fixed only (the varied look draws it from the seed)");
  if (o.vary_appearance && given("--height-jitter") && o.height_jitter < kVariedHeightJitter) {
    std::ostringstream message;
    message << "--height-jitter below " << kVariedHeightJitter
            << " m acts with --appearance fixed only (the varied look bounces at least that much)";
    throw Error(message.str());
  }
  // A value for an effect that is switched off would be silently ignored.
  struct ValueOfSwitchedOffEffect {
    const char* option;
    const char* off_flag;
    bool off;
  };
  for (const ValueOfSwitchedOffEffect& v : {ValueOfSwitchedOffEffect{"--noise-sigma", "--no-noise", args.no_noise},
                                            ValueOfSwitchedOffEffect{"--vignetting", "--no-vignetting", args.no_vignetting},
                                            ValueOfSwitchedOffEffect{"--right-vignetting", "--no-vignetting",
                                                                     args.no_vignetting},
                                            ValueOfSwitchedOffEffect{"--exposure-sigma", "--no-exposure-drift",
                                                                     args.no_exposure}}) {
    Require(!(v.off && given(v.option)), std::string(v.option) + " has no effect with " + v.off_flag);
  }
  Require(!(given("--speed") && !o.trajectory_path.empty()),
          "--speed sets the generated path's speed: it has no effect with --trajectory");
  o.Check();
  Require(args.raw_layout == "none" || args.raw_layout == "sync" || args.raw_layout == "extract",
          "--raw-layout must be none, sync or extract");
  Require(args.raw_layout != "none" || (args.raw_out.empty() && !given("--raw-drive")),
          "--raw-out / --raw-drive need --raw-layout sync|extract");
  Require(args.raw_drop_every >= 0, "--raw-drop-every must be >= 0");
  Require(args.raw_drop_every == 0 || args.raw_layout == "extract", "--raw-drop-every needs --raw-layout extract");
  args.raw.extract = args.raw_layout == "extract";
  if (args.raw_drop_every > 0) {
    // Frame 0 is kept, so the drive always starts with a stereo pair.
    for (int i = args.raw_drop_every; i < (o.num_frames < 0 ? 1000000 : o.num_frames); i += args.raw_drop_every) {
      args.raw.right_dropped.push_back(i);
    }
  }
  args.raw.Check();
  const auto& c = o.camera.left;
  std::cout << "output      : " << args.output_dir << "\n"
            << "trajectory  : " << (o.trajectory_path.empty() ? "generated driving path" : o.trajectory_path)
            << " (first " << o.first_frame << ", count " << o.num_frames << ", stride " << o.stride << ")\n"
            << "camera      : " << c.width << "x" << c.height << " fx " << c.fx << " fy " << c.fy << " cx " << c.cx
            << " cy " << c.cy << " baseline " << o.camera.baseline << " m, height " << o.camera_height << " m\n"
            << "photometric : exposure drift " << (o.exposure_drift ? "on" : "off") << ", vignetting "
            << (o.vignetting ? "on" : "off") << ", noise " << (o.noise ? "sigma " + std::to_string(o.noise_sigma) : "off")
            << "\n"
            << "world       : seed " << o.seed << ", buildings " << o.scene.building_density << ", cars "
            << o.scene.car_density << ", trees " << o.scene.tree_density << ", shadows " << (o.scene.shadows ? "on" : "off")  << ", colour " << (o.color ? "on" : "off")
            << ", appearance " << args.appearance << ", threads " << o.num_threads << "\n";
  const std::string raw_root = args.raw_out.empty() ? JoinPath(args.output_dir, "kitti_raw") : args.raw_out;
  // A drive that may not be written fails now, not after minutes of rendering.
  if (args.raw_layout != "none") CheckKittiRawDriveWritable(raw_root, args.raw, KittiCalibrationAsReadBack(o.camera));
  const SimulationSummary summary = WriteSimulatedSequence(o, args.output_dir, !args.quiet);
  std::cout << "wrote " << summary.frames << " frames (" << summary.path_length << " m) in " << summary.seconds
            << " s: " << summary.frames / std::max(summary.seconds, 1e-9) << " frames/s\n";
  if (args.raw_layout != "none") {
    const KittiRawDriveSummary raw = WriteKittiRawDrive(args.output_dir, raw_root, args.raw, !args.quiet);
    std::cout << "raw drive   : " << raw.drive_dir << " (" << raw.frames << " frames, " << raw.right_dropped
              << " dropped by the right camera" << (raw.color ? "s" : "") << ", "
              << raw.velodyne_points / std::max(raw.frames, 1) << " Velodyne points/scan, OXTS)\n";
  }
}

}  // namespace

void AddSimulateCommand(CLI::App& app) {
  auto args = std::make_shared<SimulateArgs>();
  auto* cmd = app.add_subcommand(
      "simulate", "Render a synthetic KITTI-like stereo sequence with exact ground truth (KITTI odometry layout)");
  SimulatorOptions& o = args->options;
  cmd->add_option("--out,-o", args->output_dir, "output folder (KITTI odometry layout)")->required();
  cmd->add_option("--trajectory", o.trajectory_path,
                  "KITTI pose file to follow (e.g. data/kitti_poses/00.txt); default: a generated driving path")
      ->check(CLI::ExistingFile);
  cmd->add_option("--first", o.first_frame, "first trajectory pose to render")->capture_default_str();
  cmd->add_option("--count", o.num_frames, "number of frames (-1: until the end of the trajectory)")
      ->capture_default_str();
  cmd->add_option("--stride", o.stride, "use every n-th pose")->capture_default_str();
  cmd->add_option("--seed", o.seed, "seed of the world, textures, exposure and noise")->capture_default_str();
  cmd->add_option("--speed", o.generated_speed, "speed of the generated path (m/s)")->capture_default_str();
  cmd->add_option("--width", args->width, "image width (intrinsics scaled from KITTI 00-02)");
  cmd->add_option("--height", args->height, "image height (intrinsics scaled from KITTI 00-02)");
  cmd->add_option("--fx", args->fx, "focal length x (px), overrides")->check(Positive());
  cmd->add_option("--fy", args->fy, "focal length y (px), overrides")->check(Positive());
  cmd->add_option("--cx", args->cx, "principal point x (px), overrides")->check(NonNegative());
  cmd->add_option("--cy", args->cy, "principal point y (px), overrides")->check(NonNegative());
  cmd->add_option("--baseline", args->baseline, "stereo baseline (m), default 0.537")->check(Positive());
  cmd->add_option("--camera-height", o.camera_height, "camera height above the road (m)")->capture_default_str();
  cmd->add_flag("--no-exposure-drift", args->no_exposure, "constant exposure (no per-frame gain/bias drift)");
  cmd->add_option("--exposure-sigma", o.exposure_sigma, "per-frame log-gain random-walk std")->capture_default_str();
  cmd->add_option("--right-gain", o.right_gain, "gain of the right camera relative to the left (0.5..2)")
      ->capture_default_str();
  cmd->add_option("--right-bias", o.right_bias, "extra brightness offset of the right camera (grey levels)")
      ->capture_default_str();
  cmd->add_flag("--no-vignetting", args->no_vignetting, "no vignetting");
  cmd->add_option("--vignetting", o.vignetting_strength, "vignetting fall-off at the corners (0..1)")
      ->capture_default_str();
  cmd->add_option("--right-vignetting", o.right_vignetting_strength,
                  "the right camera's own fall-off at the corners (0..1; default: the left one's)");
  cmd->add_flag("--no-noise", args->no_noise, "no sensor noise");
  cmd->add_option("--noise-sigma", o.noise_sigma, "sensor noise std (grey levels)")->capture_default_str();
  cmd->add_flag("--color", o.color, "also write colour images image_2/ image_3/");
  cmd->add_flag("--no-shadows", args->no_shadows, "no cast sun shadows");
  cmd->add_flag("--no-edge-aa", args->no_edge_aa, "no extra samples on silhouette pixels (faster, aliased edges)");
  cmd->add_option("--world-version", o.world_version,
                  "render the world of this simulator version, exactly (1: before session 38; 2: the recorded "
                  "altitude drift corrected where the path comes back to a place, GT poses the corrected ones; 3: "
                  "the invented streets beyond the path's ends yield to the driven path; 4: edge anti-aliasing puts no sky "
                  "below the horizon; core/simulator.h)")
      ->capture_default_str();
  cmd->add_option("--building-density", o.scene.building_density, "fraction of the street lined by buildings")
      ->capture_default_str();
  cmd->add_option("--car-density", o.scene.car_density, "fraction of parking lanes with cars")->capture_default_str();
  std::ostringstream car_detail_help;
  car_detail_help << "share of cars whose paint shows reflections, dirt and handles (< 0: the appearance's own, "
                  << "fixed 0, varied drawn in [" << sim::kVariedCarDetailMin << ", 1])";
  cmd->add_option("--car-detail", o.car_detail, car_detail_help.str())->capture_default_str();
  cmd->add_option("--tree-density", o.scene.tree_density, "relative amount of vegetation")->capture_default_str();
  cmd->add_option("--max-distance", o.max_distance, "drawing distance (m)")->capture_default_str();
  cmd->add_option("--threads", o.num_threads, "render threads")->capture_default_str();
  cmd->add_option("--texture-size", o.texture_size, "procedural texture resolution (power of two)")
      ->capture_default_str();
  cmd->add_option("--exposure-level", o.exposure_level, "overall camera gain")->capture_default_str();
  cmd->add_option("--height-jitter", o.height_jitter, "camera height bounce bound (m; GT poses include it)")
      ->capture_default_str();
  cmd->add_option("--appearance", args->appearance,
                  "fixed: the original look; varied: light, sky, colours, textures, car shapes, exposure and "
                  "camera height drawn from the seed")
      ->check(CLI::IsMember({"fixed", "varied"}))
      ->capture_default_str();
  cmd->add_option("--raw-layout", args->raw_layout,
                  "also write the sequence as a KITTI raw drive: sync (rectified) or extract (distorted, "
                  "unrectified), with Velodyne scans, OXTS packets and calibration (core/kitti_raw_writer.h)")
      ->capture_default_str();
  cmd->add_option("--raw-out", args->raw_out,
                  "root of the raw date folder (default OUT/kitti_raw); a drive folder an earlier simulation wrote "
                  "there is replaced, any other existing one is refused");
  cmd->add_option("--raw-drive", args->raw.drive,
                  "drive number of the raw drive (DATE_drive_NNNN_sync|extract): several simulations of one camera "
                  "can share a --raw-out; the date folder's calibration files are never replaced when another "
                  "drive reads them")
      ->capture_default_str();
  cmd->add_option("--raw-drop-every", args->raw_drop_every,
                  "extract drives: the right cameras lose every n-th frame (0 = none)")
      ->capture_default_str();
  cmd->add_flag("--quiet", args->quiet, "no progress bar");
  cmd->callback([args, cmd] {
    for (const char* option : kCheckedOptions) {
      if (cmd->count(option) > 0) args->given.insert(option);
    }
    Run(*args);
  });
}

}  // namespace dvso::cli
