#include "core/simulator_shadows.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace dvso::sim {
namespace {

float Smoothstep(double x) {
  const float t = static_cast<float>(std::clamp(x, 0.0, 1.0));
  return t * t * (3 - 2 * t);
}

// Penumbra width (m) at distance t from the occluder: the sun's disc is
// ~0.53 degrees wide; a few centimetres more keep edges smooth on screen.
double Penumbra(double t) { return 0.06 + 0.0093 * t; }

}  // namespace

ShadowCasters::ShadowCasters(std::vector<ShadowBox> boxes, std::vector<ShadowEllipsoid> ellipsoids,
                             const Eigen::Vector3d& down, const Eigen::Vector3d& to_sun)
    : boxes_(std::move(boxes)), ellipsoids_(std::move(ellipsoids)), down_(down), to_sun_(to_sun) {
  const double sun_up = -to_sun_.dot(down_);
  Require(sun_up > 0.05, "the sun must be above the horizon");
  axis_a_ = down_.unitOrthogonal();
  axis_b_ = down_.cross(axis_a_);
  // Horizontal shift of a shadow per metre of occluder height.
  const Eigen::Vector3d sun_flat = to_sun_ + sun_up * down_;
  const Eigen::Vector2d shift(-sun_flat.dot(axis_a_) / sun_up, -sun_flat.dot(axis_b_) / sun_up);
  // Bounding rectangle (a, b) of each caster's shadow.
  struct Rect {
    double a0, a1, b0, b1;
  };
  std::vector<Rect> rects;
  auto add_points = [&](const std::vector<Eigen::Vector3d>& points, double height) {
    Rect r{1e300, -1e300, 1e300, -1e300};
    for (const auto& p : points) {
      const double a = p.dot(axis_a_), b = p.dot(axis_b_);
      for (double h : {0.0, height}) {
        r.a0 = std::min(r.a0, a + h * shift.x());
        r.a1 = std::max(r.a1, a + h * shift.x());
        r.b0 = std::min(r.b0, b + h * shift.y());
        r.b1 = std::max(r.b1, b + h * shift.y());
      }
    }
    rects.push_back(r);
  };
  for (const auto& box : boxes_) {
    std::vector<Eigen::Vector3d> corners;
    for (int i = 0; i < 8; ++i)
      corners.push_back(box.center + ((i & 1) ? 1 : -1) * box.half[0] * box.axis[0] +
                        ((i & 2) ? 1 : -1) * box.half[1] * box.axis[1] + ((i & 4) ? 1 : -1) * box.half[2] * box.axis[2]);
    add_points(corners, 2 * box.half[2] + 3.0);
  }
  for (const auto& e : ellipsoids_) {
    std::vector<Eigen::Vector3d> extremes;
    for (int s : {-1, 1}) {
      extremes.push_back(e.center + s * e.radius_h * axis_a_);
      extremes.push_back(e.center + s * e.radius_h * axis_b_);
    }
    add_points(extremes, e.radius_v + 8.0);  // crowns stand at most ~8 m above the ground
  }
  if (rects.empty()) return;
  double a0 = 1e300, a1 = -1e300, b0 = 1e300, b1 = -1e300;
  for (const auto& r : rects) {
    a0 = std::min(a0, r.a0);
    a1 = std::max(a1, r.a1);
    b0 = std::min(b0, r.b0);
    b1 = std::max(b1, r.b1);
  }
  while ((a1 - a0) / cell_ * (b1 - b0) / cell_ > 4e6) cell_ *= 2;
  min_a_ = static_cast<int>(std::floor(a0 / cell_));
  min_b_ = static_cast<int>(std::floor(b0 / cell_));
  cells_a_ = static_cast<int>(std::floor(a1 / cell_)) - min_a_ + 1;
  cells_b_ = static_cast<int>(std::floor(b1 / cell_)) - min_b_ + 1;
  grid_.assign(static_cast<size_t>(cells_a_) * cells_b_, {});
  for (int id = 0; id < static_cast<int>(rects.size()); ++id) {
    const Rect& r = rects[id];
    for (int ia = static_cast<int>(std::floor(r.a0 / cell_)); ia <= static_cast<int>(std::floor(r.a1 / cell_)); ++ia)
      for (int ib = static_cast<int>(std::floor(r.b0 / cell_)); ib <= static_cast<int>(std::floor(r.b1 / cell_)); ++ib)
        grid_[static_cast<size_t>(ia - min_a_) * cells_b_ + (ib - min_b_)].push_back(id);
  }
}

float ShadowCasters::Occlusion(const Eigen::Vector3d& p, int skip) const {
  if (grid_.empty()) return 0.f;
  const int ia = static_cast<int>(std::floor(p.dot(axis_a_) / cell_)) - min_a_;
  const int ib = static_cast<int>(std::floor(p.dot(axis_b_) / cell_)) - min_b_;
  if (ia < 0 || ib < 0 || ia >= cells_a_ || ib >= cells_b_) return 0.f;
  float occlusion = 0.f;
  const int num_boxes = static_cast<int>(boxes_.size());
  for (int id : grid_[static_cast<size_t>(ia) * cells_b_ + ib]) {
    if (id == skip) continue;
    if (id < num_boxes) {
      // Slab test of the ray p + t * to_sun (t > 0) in the box frame.
      const ShadowBox& box = boxes_[id];
      const Eigen::Vector3d d = p - box.center;
      double t0 = 0.0, t1 = 1e300;
      for (int k = 0; k < 3 && t0 <= t1; ++k) {
        const double o = d.dot(box.axis[k]), v = to_sun_.dot(box.axis[k]);
        if (std::abs(v) < 1e-12) {
          if (std::abs(o) > box.half[k]) t1 = -1;
          continue;
        }
        const double ta = (-box.half[k] - o) / v, tb = (box.half[k] - o) / v;
        t0 = std::max(t0, std::min(ta, tb));
        t1 = std::min(t1, std::max(ta, tb));
      }
      if (t1 <= t0) continue;
      // Soft edge: how deep inside the box the ray passes (at the middle of
      // its chord) grows from 0 at the box's silhouette.
      const double tm = 0.5 * (t0 + t1);
      double depth = 1e300;
      for (int k = 0; k < 3; ++k)
        depth = std::min(depth, box.half[k] - std::abs(d.dot(box.axis[k]) + tm * to_sun_.dot(box.axis[k])));
      occlusion = std::max(occlusion, Smoothstep(depth / (0.5 * Penumbra(t0))));
    } else {
      const ShadowEllipsoid& e = ellipsoids_[id - num_boxes];
      // Scale the vertical axis to turn the ellipsoid into a unit sphere.
      const double k = e.radius_h / e.radius_v;
      Eigen::Vector3d o = p - e.center, v = to_sun_;
      o += (k - 1) * o.dot(down_) * down_;
      v += (k - 1) * v.dot(down_) * down_;
      const double vv = v.squaredNorm(), ov = o.dot(v);
      const double closest_sq = o.squaredNorm() - ov * ov / vv;  // squared distance of the ray to the centre
      const double r2 = e.radius_h * e.radius_h;
      if (closest_sq >= r2 || ov > 0) continue;  // misses, or the centre lies behind p
      const double chord = 2 * std::sqrt(r2 - closest_sq);
      occlusion = std::max(occlusion, static_cast<float>(e.opacity) * Smoothstep(chord / (0.3 * e.radius_h + Penumbra(-ov / std::sqrt(vv)))));
    }
    if (occlusion >= 0.999f) break;
  }
  return occlusion;
}

}  // namespace dvso::sim
