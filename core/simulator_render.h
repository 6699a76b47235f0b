// Software renderer of the synthetic street: a tiled, multi-threaded
// rasteriser fills a visibility buffer (nearest triangle per pixel, z-test on
// the exact inverse depth of the triangle's plane), then every visible pixel
// is shaded once: exact ray-plane hit -> filtered texture lookups with
// analytic pixel footprints (anti-aliasing) -> Lambertian light that does not
// depend on the viewpoint -> camera model (exposure, vignetting, noise).
// Pixels on silhouettes and creases get 4 extra sub-samples (edge AA).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <opencv2/core.hpp>

#include "core/camera.h"
#include "core/simulator_scene.h"
#include "core/simulator_textures.h"

namespace dvso::sim {

// Camera response of one image (DSO's affine brightness model plus
// vignetting and additive Gaussian noise): I = clamp(gain * 255 * V(x) * L + bias + n).
struct Photometric {
  double gain = 1.0;                // exposure gain (e^a in DSO's affine model)
  double bias = 0.0;                // additive brightness offset (grey levels)
  double vignetting_strength = 0;   // V(x) = 1 - strength * rho^2 (RadialVignette{{-strength}}, core/vignette.h)
  double noise_sigma = 0;           // std of additive noise (grey levels); 0 = none
  uint64_t noise_seed = 0;          // noise stream (frame and view specific)
};

struct RenderedView {
  cv::Mat grey;   // CV_8UC1
  cv::Mat color;  // CV_8UC3 BGR; only when colour was requested
  cv::Mat depth;  // CV_32FC1, metres along the optical axis; 0 = sky / nothing
};

// Radiance of surfaces and sky (simulator_shading.cpp).
class Shader {
 public:
  Shader(const Scene& scene, const TextureBank& textures) : scene_(scene), textures_(textures) {}
  // Linear RGB radiance (about 0..1) of a surface point; dPdx/dPdy: world
  // displacement of the hit point per pixel along image x / y.
  Eigen::Vector3f Surface(const Triangle& triangle, const Eigen::Vector3d& point, const Eigen::Vector3d& dPdx,
                          const Eigen::Vector3d& dPdy) const;
  // Sky radiance along a (unit) world direction; pixel_angle in radians.
  Eigen::Vector3f Sky(const Eigen::Vector3d& direction, double pixel_angle) const;

 private:
  const Scene& scene_;
  const TextureBank& textures_;
};

class Renderer {
 public:
  // max_distance: geometry farther than this (m, along the optical axis) is not drawn.
  // edge_antialiasing: 4 extra samples on pixels at depth edges and creases.
  // uncovered_subsamples_see_sky: such a sample that hits none of the surfaces seen at the 3x3 pixel
  // centres around it shades sky, as in simulator world versions 1-3 (core/simulator.h); false
  // (version 4): sky only when one of those centres sees sky, else the sample is left out.
  Renderer(const Scene& scene, const TextureBank& textures, const PinholeCamera& camera, int num_threads,
           double max_distance, bool edge_antialiasing = true, bool uncovered_subsamples_see_sky = false);

  // Renders the view of a camera at T_world_camera (camera-to-world, camera y down).
  RenderedView Render(const Eigen::Isometry3d& T_world_camera, const Photometric& photometric,
                      bool with_color) const;

 private:
  const Scene& scene_;
  Shader shader_;
  PinholeCamera camera_;
  int num_threads_;
  double max_distance_;
  bool edge_antialiasing_;
  bool uncovered_subsamples_see_sky_;
};

}  // namespace dvso::sim
