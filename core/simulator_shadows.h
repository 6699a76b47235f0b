// Cast sun shadows of the synthetic street: buildings, cars and hedges as
// oriented boxes, tree crowns as ellipsoids. A shadow is a property of the
// surface point (the sun is fixed), so it keeps every view photo-consistent.
// Occluders are registered in a 2D grid over the cells their shadows can
// reach; a shaded pixel tests the few occluders of its cell with a soft
// (chord-length based) penumbra, so shadow edges are not aliased.
#pragma once

#include <Eigen/Geometry>
#include <vector>

namespace dvso::sim {

struct ShadowBox {
  Eigen::Vector3d center;             // box centre
  Eigen::Vector3d axis[3];            // unit axes (forward, right, up)
  double half[3] = {0.5, 0.5, 0.5};   // half extents along the axes
};

struct ShadowEllipsoid {
  Eigen::Vector3d center;
  double radius_h = 1, radius_v = 1;  // horizontal / vertical radius
  double opacity = 0.85;              // foliage lets some light through
};

class ShadowCasters {
 public:
  ShadowCasters() = default;
  // down: world down; to_sun: unit vector towards the sun (above the horizon).
  ShadowCasters(std::vector<ShadowBox> boxes, std::vector<ShadowEllipsoid> ellipsoids, const Eigen::Vector3d& down,
                const Eigen::Vector3d& to_sun);

  // Fraction of the sun blocked at world point p (0 = lit, 1 = full shadow).
  // `skip` is the caster id of the surface itself (see CasterId), or -1.
  float Occlusion(const Eigen::Vector3d& p, int skip) const;

  // Caster ids: boxes first, then ellipsoids.
  static int BoxId(int i) { return i; }
  int EllipsoidId(int i) const { return static_cast<int>(boxes_.size()) + i; }
  bool empty() const { return boxes_.empty() && ellipsoids_.empty(); }

 private:
  std::vector<ShadowBox> boxes_;
  std::vector<ShadowEllipsoid> ellipsoids_;
  Eigen::Vector3d down_ = Eigen::Vector3d::UnitY(), to_sun_ = -Eigen::Vector3d::UnitY();
  Eigen::Vector3d axis_a_ = Eigen::Vector3d::UnitX(), axis_b_ = Eigen::Vector3d::UnitZ();
  double cell_ = 8.0;
  int min_a_ = 0, min_b_ = 0, cells_a_ = 0, cells_b_ = 0;
  std::vector<std::vector<int>> grid_;  // caster ids per cell
};

}  // namespace dvso::sim
