// `dvso simulate`: a synthetic KITTI-like stereo world with exact ground
// truth. A procedural street (road with markings, curbs, sidewalks, facades
// with gaps, parked cars, poles, signs, trees, sky) is laid along a KITTI
// trajectory or a generated driving path and rendered for a rectified stereo
// camera (KITTI 00-02 intrinsics by default), with per-frame exposure drift,
// vignetting and sensor noise. Output: the KITTI odometry layout plus
// poses.txt, depth_0/, disp_0/ and disp_1/ (see docs/simulator.md).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/simulator_render.h"
#include "core/simulator_scene.h"

namespace dvso {

// Which world given options render. Bumped whenever the same options and seed render another world; every
// version stays renderable (SimulatorOptions::world_version, `dvso simulate --world-version`), so a model's
// training worlds can be rendered again exactly, and scripts caching worlds (scripts/train_stacknet.sh,
// benchmarks/run_label_worlds.sh) can tell a stale one. Written to simulation.yaml as `world_version` and
// printed by `dvso --version`.
//   1: before session 38 (simulation.yaml has no world_version and no reconcile_altitude: true)
//   2: altitude drift of recorded paths reconciled at revisits (session 38; its simulation.yaml says
//      `reconcile_altitude: true`)
//   3: the invented streets before the first / after the last pose yield to the driven path (session 39)
//   4: an anti-aliasing sub-sample of an edge pixel that hits none of the surfaces seen around it is left
//      out, not painted as sky (session 40; a bright fringe below the horizon at far kerbs and object feet)
constexpr int kSimulatorWorldVersion = 4;
constexpr double kVariedCameraHeightRange = 0.1;  // varied look: camera height = camera_height +- this (m)
constexpr double kVariedHeightJitter = 0.03;      // varied look: per-frame height bounce bound at least this (m)

struct SimulatorOptions {
  std::string trajectory_path;      // KITTI pose file (camera-to-world); empty = generated driving path
  int first_frame = 0;              // index of the first trajectory pose rendered
  int num_frames = 300;             // frames to render; -1 = until the end of the trajectory
  int stride = 1;                   // use every stride-th pose
  double generated_speed = 10.0;    // m/s of the generated path (no trajectory file)
  uint64_t seed = 1;                // world layout, textures, exposure and noise
  StereoCamera camera;              // rectified stereo camera (KITTI 00-02 defaults)
  double car_detail = -1;           // share of cars with detailed paint (reflections, dirt); < 0: the look's
                                    //   own (fixed: 0, varied: drawn from the seed in [kVariedCarDetailMin, 1])
  double camera_height = 1.65;      // camera height above the road (m, KITTI)
  // The world of this version (1..kSimulatorWorldVersion, history above). From 2 the trajectory's
  // altitude drift is corrected where the path comes back to a place, so that the camera stays
  // camera_height above the one street laid there (sim::AltitudeCorrections; GT poses are the
  // corrected ones); from 3 the invented streets beyond the path's ends yield to the driven path
  // (SceneOptions::extensions_yield, set from this by the constructor); from 4 no sky below the horizon
  // in the anti-aliasing of edge pixels (Renderer's uncovered_subsamples_see_sky).
  int world_version = kSimulatorWorldVersion;
  double frame_interval = 0.1;      // seconds between trajectory poses (times.txt)
  double max_distance = 300.0;      // nothing farther than this is drawn (m)
  sim::SceneOptions scene;          // densities of buildings, cars, trees
  bool exposure_drift = true;       // per-frame affine brightness drift (DSO's a, b)
  double exposure_sigma = 0.03;     // std of the per-frame log-gain random-walk step
  double exposure_max = 0.35;       // bound on |log gain|
  double bias_sigma = 0.6;          // std of the per-frame bias random-walk step (grey levels)
  // The right camera's own response (a real rig's two sensors differ in gain and black level; Stereo DSO
  // estimates an affine brightness per image for that reason): the right view is rendered with gain
  // gain_i * right_gain and bias b_i + right_bias, so I_right = right_gain * (I_left - b_i) + b_i + right_bias
  // for the same radiance and vignetting.
  double right_gain = 1.0;          // gain of the right camera relative to the left
  double right_bias = 0.0;          // extra brightness offset of the right camera (grey levels)
  bool vignetting = true;           // radial fall-off V(r) = 1 - strength (r / r_corner)^2
  double vignetting_strength = 0.3; // fall-off at the image corners
  // The right camera's own fall-off (lenses and sensors of a rig differ; a radial difference is what an
  // affine brightness transfer between the two images cannot absorb); < 0 = the left one's.
  double right_vignetting_strength = -1;
  bool noise = true;                // additive Gaussian sensor noise
  double noise_sigma = 1.5;         // noise std (grey levels)
  bool color = false;               // also render image_2/ image_3/ (colour)
  bool edge_antialiasing = true;    // 4 extra samples on silhouette / crease pixels
  int num_threads = 2;              // render threads
  int texture_size = 512;           // procedural texture resolution (power of two)
  double exposure_level = 0.85;     // overall gain of the camera model (head room for bright facades and sky)
  double height_jitter = 0.0;       // camera height bounce (m, bound of a smooth per-frame offset); GT poses include it
  // Varied look drawn from the seed: scene.appearance = RandomAppearance(seed),
  // exposure level 0.6-1.1 (replacing exposure_level), camera_height + a random
  // +-kVariedCameraHeightRange, height jitter at least kVariedHeightJitter (applied
  // by the constructor; `dvso simulate --appearance varied`, which therefore refuses
  // an explicit --exposure-level, or a --height-jitter below that minimum, beside it).
  bool vary_appearance = false;

  // Throws dvso::Error naming the offending option.
  void Check() const;
};

// One rendered stereo frame with its ground truth.
struct SimulatedFrame {
  int index = 0;                  // output frame index (0-based)
  int pose_index = 0;             // index into the trajectory
  double timestamp = 0;           // seconds
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();  // trajectory frame
  Eigen::Isometry3d T_first_camera = Eigen::Isometry3d::Identity();  // relative to output frame 0 (poses.txt)
  sim::Photometric photometric;   // exposure of this frame (left view)
  sim::RenderedView left, right;  // images and depth (0 = sky)
  cv::Mat disparity_left;         // CV_32F, fx*b/depth of the left view (0 = sky); right x = left x - d
  cv::Mat disparity_right;        // CV_32F, the right view's own disparity: left x = right x + d
};

class StreetSimulator {
 public:
  explicit StreetSimulator(const SimulatorOptions& options);
  ~StreetSimulator();

  int num_frames() const { return static_cast<int>(frame_poses_.size()); }
  const SimulatorOptions& options() const { return options_; }
  const StereoCamera& camera() const { return options_.camera; }
  const sim::Scene& scene() const { return scene_; }
  // Camera-to-world pose of output frame i's left camera (as rendered).
  Eigen::Isometry3d WorldFromCamera(int i) const;
  // Renders output frame i (0 <= i < num_frames()); thread-safe, deterministic.
  SimulatedFrame Render(int i) const;
  // Exposure of output frame i.
  sim::Photometric Exposure(int i, int view) const;

 private:
  SimulatorOptions options_;
  std::vector<int> frame_poses_;                  // trajectory index of each output frame
  std::vector<Eigen::Isometry3d> trajectory_;     // all poses, camera-to-world
  std::vector<double> log_gain_, bias_;           // per output frame
  std::vector<double> height_offset_;             // camera offset along "down" per output frame (m)
  std::unique_ptr<sim::StreetPath> path_;
  std::unique_ptr<sim::TextureBank> textures_;
  sim::Scene scene_;
  std::unique_ptr<sim::Renderer> renderer_;
};

struct SimulationSummary {
  int frames = 0;          // frames written
  double seconds = 0;      // wall time of rendering and writing
  double path_length = 0;  // metres driven between the first and last frame
};

// Renders all frames and writes the KITTI odometry layout into output_dir,
// frame by frame (each file atomically). Prints a progress bar when asked.
SimulationSummary WriteSimulatedSequence(const SimulatorOptions& options, const std::string& output_dir,
                                         bool show_progress);

}  // namespace dvso
