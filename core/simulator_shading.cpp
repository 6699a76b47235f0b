// Materials and light. Radiance depends only on the surface point (albedo
// texture, overlays, normal, fixed sun and sky light), never on the viewing
// direction: a Lambertian world is what the photometric-consistency
// assumption of DSO (paper eq. 5.1) and of the left-right reconstruction loss
// expects, so left/right/temporal views of a point agree up to noise.
#include <algorithm>
#include <cmath>

#include "core/simulator_render.h"

namespace dvso::sim {
namespace {

// Fraction of a box filter of width `footprint` centred at x that covers the
// band [lo, hi] (analytic anti-aliasing of painted lines).
float BandCoverage(double x, double footprint, double lo, double hi) {
  const double f = std::max(footprint, 1e-4);
  const double cover = std::min(x + f / 2, hi) - std::max(x - f / 2, lo);
  return static_cast<float>(std::clamp(cover / f, 0.0, 1.0));
}

float Smoothstep(float x) {
  x = std::clamp(x, 0.f, 1.f);
  return x * x * (3 - 2 * x);
}

}  // namespace

Eigen::Vector3f Shader::Surface(const Triangle& triangle, const Eigen::Vector3d& point, const Eigen::Vector3d& dPdx,
                                const Eigen::Vector3d& dPdy) const {
  const sim::Surface& s = scene_.surfaces[triangle.surface];
  const Eigen::Vector3d rel = point - s.origin;
  const double u = s.axis_u.dot(rel), v = s.axis_v.dot(rel);
  const float dudx = static_cast<float>(s.axis_u.dot(dPdx)), dvdx = static_cast<float>(s.axis_v.dot(dPdx));
  const float dudy = static_cast<float>(s.axis_u.dot(dPdy)), dvdy = static_cast<float>(s.axis_v.dot(dPdy));
  const MipTexture& detail = textures_[s.texture];
  float albedo = s.max_taps > 1 ? detail.SampleAniso(u, v, dudx, dvdx, dudy, dvdy, s.max_taps)
                                : detail.Sample(u, v,
                                                std::sqrt(std::max(dudx * dudx + dvdx * dvdx, dudy * dudy + dvdy * dvdy)) *
                                                    detail.size());
  if (s.macro_strength > 0) {
    const MipTexture& macro = textures_[kTexMacro];
    const float fp = std::sqrt(std::max(dudx * dudx + dvdx * dvdx, dudy * dudy + dvdy * dvdy)) * s.macro_scale *
                     macro.size();
    const float m = macro.Sample(u * s.macro_scale + 0.37, v * s.macro_scale + 0.61, fp);
    albedo *= 1.f + s.macro_strength * 2.f * (m - 0.5f);
  }
  switch (s.overlay) {
    case Overlay::kRoadMarkings: {
      const Eigen::Vector3d d = point - s.frame_origin;
      const double lateral = s.frame_right.dot(d);
      const double along = s.frame_s0 + s.frame_tangent.dot(d);
      const double fl = std::abs(s.frame_right.dot(dPdx)) + std::abs(s.frame_right.dot(dPdy));
      const double fa = std::abs(s.frame_tangent.dot(dPdx)) + std::abs(s.frame_tangent.dot(dPdy));
      float paint = 0;
      if (s.overlay_flags & 1) {  // dashed centre line: 3 m dash, 6 m gap
        const double phase = along - 9.0 * std::floor(along / 9.0);
        const float dash = std::max(BandCoverage(phase, fa, 0.0, 3.0), BandCoverage(phase - 9.0, fa, 0.0, 3.0));
        paint = std::max(paint, dash * BandCoverage(lateral, fl, -1.81, -1.69));
      }
      if (s.overlay_flags & 2) paint = std::max(paint, BandCoverage(lateral, fl, s.overlay_a + 0.3, s.overlay_a + 0.45));
      if (s.overlay_flags & 4) paint = std::max(paint, BandCoverage(lateral, fl, s.overlay_b - 0.45, s.overlay_b - 0.3));
      if ((s.overlay_flags & 8) && lateral > s.overlay_a + 0.3 && lateral < s.overlay_b - 0.3) {
        // Zebra stripes 0.5 m wide every metre, parallel to the driving direction.
        const double phase = lateral - std::floor(lateral);
        paint = std::max(paint, std::max(BandCoverage(phase, fl, 0.25, 0.75), 0.f));
      }
      if (paint > 0) albedo += paint * (0.55f + 0.6f * (albedo - 0.36f) - albedo);
      break;
    }
    case Overlay::kPlinth: {
      const double height = v * s.overlay_c - s.overlay_b;  // metres above the sidewalk
      if (height < s.overlay_a) albedo *= 0.55f;
      break;
    }
    case Overlay::kShadow: {
      const Eigen::Vector3d d = point - s.frame_origin;
      const float a = static_cast<float>(std::abs(s.frame_tangent.dot(d)));
      const float b = static_cast<float>(std::abs(s.frame_right.dot(d)));
      albedo *= 1.f - 0.6f * Smoothstep((s.overlay_a - a) / 0.6f) * Smoothstep((s.overlay_b - b) / 0.5f);
      break;
    }
    case Overlay::kNone:
      break;
  }
  // Shading normal (viewpoint independent).
  Eigen::Vector3d n = triangle.normal;
  if (s.normal_mode == NormalMode::kEllipsoid) {
    const Eigen::Vector3d d = point - s.shape_center;
    const double dv = d.dot(scene_.down);
    const Eigen::Vector3d m = (d - dv * scene_.down) / (s.shape_radii.x() * s.shape_radii.x()) +
                              scene_.down * (dv / (s.shape_radii.y() * s.shape_radii.y()));
    if (m.squaredNorm() > 1e-12) n = m.normalized();
  } else if (s.normal_mode == NormalMode::kCylinder) {
    const Eigen::Vector3d d = point - s.shape_center;
    const Eigen::Vector3d m = d - d.dot(scene_.down) * scene_.down;
    if (m.squaredNorm() > 1e-12) n = m.normalized();
  }
  const Appearance& look = scene_.appearance;
  const double upness = -n.dot(scene_.down);  // 1 for ground, 0 for walls
  const float sky_light = static_cast<float>(look.sky_light + look.sky_light_up * upness);
  float sun_light = static_cast<float>(look.sun_strength * std::max(0.0, n.dot(scene_.to_sun)));
  if (sun_light > 0 && !scene_.shadows.empty()) {
    const int skip = s.caster_box >= 0 ? ShadowCasters::BoxId(s.caster_box)
                                       : (s.caster_ellipsoid >= 0 ? scene_.shadows.EllipsoidId(s.caster_ellipsoid) : -1);
    sun_light *= 1.f - scene_.shadows.Occlusion(point + 0.02 * triangle.normal, skip);
  }
  if (!look.varied) return s.tint * (albedo * (sky_light + sun_light));
  return s.tint.cwiseProduct(look.light_colour) * (albedo * (sky_light + sun_light));
}

Eigen::Vector3f Shader::Sky(const Eigen::Vector3d& direction, double pixel_angle) const {
  const double elevation = -direction.dot(scene_.down);  // sine of the elevation angle
  const float t = static_cast<float>(std::pow(std::clamp(elevation * 1.6, 0.0, 1.0), 0.7));
  const Eigen::Vector3f& horizon = scene_.appearance.sky_horizon;
  const Eigen::Vector3f& zenith = scene_.appearance.sky_zenith;
  Eigen::Vector3f sky = horizon + t * (zenith - horizon);
  if (elevation > 0.01) {
    // Clouds on a plane far above: direction -> plane coordinates.
    const double e = std::max(elevation, 0.05);
    const double k = 0.05;
    const double cu = k * direction.dot(scene_.horizontal_a) / e, cv = k * direction.dot(scene_.horizontal_b) / e;
    const MipTexture& clouds = textures_[kTexClouds];
    const float footprint = static_cast<float>(clouds.size() * k * pixel_angle / (e * e));
    const float c = clouds.Sample(cu, cv, footprint);
    const float amount = std::clamp((c - scene_.appearance.cloud_threshold) * 1.4f, 0.f, 1.f) * static_cast<float>(std::min(1.0, elevation * 5));
    sky += amount * (Eigen::Vector3f(0.97f, 0.97f, 0.98f) - sky);
  }
  return sky;
}

}  // namespace dvso::sim
