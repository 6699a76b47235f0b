// Object placement along the street: near buildings with gaps, a farther
// row of buildings or trees, parked cars, street lamps, signs, trees, hedges
// and bushes. Every object is checked against all streets of the path (loops
// and crossings included) so that nothing stands in a road or a driving lane.
#include <algorithm>
#include <cmath>
#include <random>

#include "core/simulator_scene.h"

namespace dvso::sim {
namespace {

using Vec3 = Eigen::Vector3d;

struct Placement {
  const StreetPath& path;
  const SceneOptions& options;
  SceneBuilder* builder;
  Scene* scene;
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> unit{0.0, 1.0};

  double U(double lo, double hi) { return lo + (hi - lo) * unit(rng); }
  bool Chance(double p) { return unit(rng) < p; }
  const PathSample& At(double s) const { return path.samples()[path.SampleAt(s)]; }
  // Revisits of an earlier street get no objects of their own.
  bool Merged(double s) const { return At(s).merged_into >= 0; }
  // Horizontal tangent at arc length s.
  Vec3 Point(double s, double lateral) const { return At(s).road + At(s).right * lateral; }
  double Edge(const PathSample& p, int side) const { return side == 0 ? -p.profile.left_edge : p.profile.right_edge; }
  double Walk(const PathSample& p, int side) const {
    return side == 0 ? p.profile.sidewalk_left : p.profile.sidewalk_right;
  }
  // True when none of the points along the rectangle's outline is in the zone
  // (for an object `height` metres tall standing on the rectangle).
  bool Free(const Vec3& centre, const Vec3& forward, double length, double width, Zone zone, double margin,
            double height) const {
    const Vec3 f = forward.normalized(), r = scene->down.cross(f).normalized();
    const int nl = std::max(1, static_cast<int>(std::ceil(length / 1.5)));
    const int nw = std::max(1, static_cast<int>(std::ceil(width / 1.5)));
    for (int i = 0; i <= nl; ++i)
      for (int k = 0; k <= nw; ++k) {
        if (i != 0 && i != nl && k != 0 && k != nw) continue;  // outline only
        const Vec3 q = centre + f * (length * (static_cast<double>(i) / nl - 0.5)) +
                       r * (width * (static_cast<double>(k) / nw - 0.5));
        if (path.InZone(q, zone, margin, height)) return false;
      }
    return true;
  }
  Eigen::Vector3f Colour(const std::vector<Eigen::Vector3f>& palette) {
    const auto& c = palette[static_cast<size_t>(unit(rng) * palette.size()) % palette.size()];
    const float v = static_cast<float>(U(0.9, 1.1));
    return (c * v).cwiseMin(1.f);
  }
};

Surface Textured(int texture, const Eigen::Vector3f& tint, float macro_scale, float macro_strength) {
  Surface s;
  s.texture = texture;
  s.tint = tint;
  s.macro_scale = macro_scale;
  s.macro_strength = macro_strength;
  return s;
}

const std::vector<Eigen::Vector3f> kFacadeColours = {
    {0.95f, 0.92f, 0.85f}, {0.90f, 0.80f, 0.65f}, {0.80f, 0.82f, 0.85f}, {0.95f, 0.85f, 0.75f},
    {0.75f, 0.70f, 0.65f}, {0.90f, 0.90f, 0.90f}, {0.85f, 0.75f, 0.70f}};
const std::vector<Eigen::Vector3f> kCarColours = {
    {0.95f, 0.95f, 0.95f}, {0.20f, 0.20f, 0.22f}, {0.75f, 0.76f, 0.80f}, {0.80f, 0.15f, 0.12f},
    {0.20f, 0.32f, 0.70f}, {0.55f, 0.57f, 0.60f}, {0.90f, 0.85f, 0.70f}, {0.95f, 0.95f, 0.95f},
    {0.75f, 0.76f, 0.80f}};

void AddBuilding(Placement& pl, const Vec3& front_mid, const Vec3& forward, const Vec3& inward, double length,
                 double depth, double height) {
  // One storey below the sidewalk, so that the facade tiles' storeys start at sidewalk level.
  const double below = 3.2 - pl.options.curb_height;
  const Vec3 base = front_mid + inward * (0.5 * depth) + pl.scene->down * below;
  const Appearance& look = pl.options.appearance;
  // Colour before style: the draw order of the original look (GCC evaluated the
  // arguments of the former one-line call right to left).
  Eigen::Vector3f colour = pl.Colour(kFacadeColours);
  const int style = static_cast<int>(pl.unit(pl.rng) * look.facade_styles) % look.facade_styles;
  if (look.facade_free_colour > 0 && pl.Chance(look.facade_free_colour)) {
    // Any hue, mild saturation, any brightness.
    const double hue = pl.U(0, 6), sat = pl.U(0.05, 0.5), val = pl.U(0.35, 1.0);
    const int k = static_cast<int>(hue) % 6;
    const double f = hue - std::floor(hue);
    const double p = val * (1 - sat), q = val * (1 - sat * f), t = val * (1 - sat * (1 - f));
    const double rgb[6][3] = {{val, t, p}, {q, val, p}, {p, val, t}, {p, q, val}, {t, p, val}, {val, p, q}};
    colour = Eigen::Vector3f(static_cast<float>(rgb[k][0]), static_cast<float>(rgb[k][1]), static_cast<float>(rgb[k][2]));
  }
  Surface facade = Textured(FacadeTexture(style), colour, 0.15f, 0.35f);
  facade.overlay = Overlay::kPlinth;
  facade.overlay_a = static_cast<float>(pl.U(0.4, 1.0));  // plinth height (m)
  facade.overlay_b = 3.2f;                                 // metres from the box bottom to the sidewalk
  facade.overlay_c = 6.4f;                                 // metres per texture tile
  Surface roof = Textured(kTexDirt, {0.5f, 0.45f, 0.42f}, 0.1f, 0.3f);
  roof.axis_u = pl.scene->horizontal_a / 4.0;
  roof.axis_v = pl.scene->horizontal_b / 4.0;
  pl.builder->BeginChunk();
  pl.builder->AddShadowBox(base, forward, length, depth, height + below, facade, 6.4, pl.builder->AddSurface(roof));
  pl.builder->EndChunk();
  pl.scene->num_buildings++;
}

// A row of buildings along one side; lateral range (from the curb) and
// density depend on `far`.
void BuildingRow(Placement& pl, int side, bool far, double s_begin, double s_end) {
  const double sign = side == 0 ? -1.0 : 1.0;
  double s = s_begin + pl.U(0, 10);
  while (s < s_end) {
    if (pl.Merged(s)) {
      s += 2.0;
      continue;
    }
    const PathSample& p = pl.At(s);
    const double density = far ? 0.85 : pl.options.building_density * (p.profile.green ? 0.5 : 1.0);
    if (!pl.Chance(density)) {
      s += far ? pl.U(3, 12) : pl.U(4, 16);
      continue;
    }
    double length = far ? pl.U(15, 40) : pl.U(8, 28);
    const double setback = far ? pl.U(14, 26) : (p.profile.green ? pl.U(2, 8) : pl.U(0.3, 3));
    const double depth = far ? pl.U(10, 20) : pl.U(8, 14);
    const int floors = far ? 3 + static_cast<int>(pl.U(0, 5)) : 2 + static_cast<int>(pl.U(0, 4));
    const double height = floors * 3.2 + pl.U(0.3, 1.5);
    for (int attempt = 0; attempt < 2; ++attempt, length *= 0.5) {
      const PathSample& mid = pl.At(s + length / 2);
      const double lateral = pl.Edge(mid, side) + pl.Walk(mid, side) + setback;
      const Vec3 front_mid = mid.road + mid.right * (sign * lateral);
      const Vec3 inward = mid.right * sign;
      const Vec3 centre = front_mid + inward * (depth / 2);
      if (pl.Free(centre, mid.tangent, length, depth, Zone::kStreet, 0.2, height)) {
        AddBuilding(pl, front_mid, mid.tangent, inward, length, depth, height);
        break;
      }
    }
    s += length + (far ? pl.U(0, 4) : pl.U(0, 3));
  }
}

// Body and cabin proportions of a parked car.
struct CarShape {
  double body_height;     // body box height above its 0.3 m lift (m)
  double cabin_fraction;  // cabin length / car length
  double cabin_shift;     // cabin centre behind the car centre, fraction of the length
  double cabin_height;    // m
  double min_length, max_length;  // m
};
// Sedan (the original shape), hatchback, estate, SUV, van.
constexpr CarShape kCarShapes[] = {{0.675, 0.525, 0.05, 0.50, 3.8, 4.8},  {0.65, 0.55, 0.16, 0.55, 3.4, 4.1},
                                   {0.68, 0.68, 0.12, 0.52, 4.4, 4.9},   {0.85, 0.58, 0.08, 0.62, 4.2, 4.9},
                                   {1.25, 0.78, 0.08, 0.55, 4.6, 5.4}};
constexpr int kNumCarShapes = sizeof(kCarShapes) / sizeof(kCarShapes[0]);
// Upper bound of any car's height (van: 0.3 m lift + 1.25 m body + 0.6 m cabin).
constexpr double kMaxCarHeight = 2.5;

// Uniform [0, 1) draw that decides whether a car gets the detailed paint: from the car's ground position (mm,
// spatial-hash primes) rather than from the placement generator, so every later placement draw stays what it was
// before the option existed. The worlds of configs/stacknet_cpu_v4c_long.yaml were rendered with exactly this draw.
double CarPaintDraw(const Vec3& base) {
  constexpr double kMillimetres = 1000;
  constexpr uint64_t kPrimeX = 73856093ull, kPrimeZ = 19349663ull;
  std::mt19937_64 draw(static_cast<uint64_t>(std::llround(base.x() * kMillimetres)) * kPrimeX ^
                       static_cast<uint64_t>(std::llround(base.z() * kMillimetres)) * kPrimeZ);
  return std::uniform_real_distribution<double>(0.0, 1.0)(draw);
}

void AddCar(Placement& pl, const Vec3& base, const Vec3& forward, double length, int shape) {
  const Eigen::Vector3f colour = pl.Colour(kCarColours);
  const Vec3 up = pl.builder->up();
  pl.builder->BeginChunk();
  // Contact shadow: darkened asphalt slightly above the road, same world mapping as the road.
  Surface shadow = Textured(kTexAsphalt, {0.95f, 0.95f, 1.0f}, static_cast<float>(2.5 / 37.0), 0.35f);
  shadow.axis_u = pl.scene->horizontal_a / 2.5;
  shadow.axis_v = pl.scene->horizontal_b / 2.5;
  shadow.max_taps = 4;
  shadow.overlay = Overlay::kShadow;
  shadow.frame_origin = base;
  shadow.frame_tangent = forward;
  shadow.frame_right = pl.scene->down.cross(forward).normalized();
  shadow.overlay_a = static_cast<float>(length / 2 + 0.3);
  shadow.overlay_b = 1.2f;
  const Vec3 f = forward * (length / 2 + 0.4), r = shadow.frame_right * 1.3, lift = up * 0.015;
  pl.builder->AddQuad(base - f - r + lift, base + f - r + lift, base + f + r + lift, base - f + r + lift, up,
                      pl.builder->AddSurface(shadow));
  const bool detailed = CarPaintDraw(base) < pl.options.appearance.car_detail;
  Surface paint = Textured(detailed ? kTexCarPaintDetailed : kTexCarPaint, colour, 0.3f, 0.15f);
  Surface glass = Textured(kTexCarGlass, {0.85f, 0.9f, 1.0f}, 0.2f, 0.2f);
  Surface rubber = Textured(kTexRubber, {1.f, 1.f, 1.f}, 0.f, 0.f);
  const double width = pl.U(1.7, 1.85);
  for (int axle = -1; axle <= 1; axle += 2)
    for (int wheel_side = -1; wheel_side <= 1; wheel_side += 2)
      pl.builder->AddBox(base + forward * (axle * length * 0.33) + shadow.frame_right * (wheel_side * width * 0.4),
                         forward, 0.62, 0.24, 0.36, rubber, 1.0);
  Surface roof = paint;
  roof.axis_u = forward / 2.0;
  roof.axis_v = shadow.frame_right / 2.0;
  roof.origin = base;
  if (shape < 0) {  // the original sedan, drawn exactly as before
    pl.builder->AddShadowBox(base + up * 0.3, forward, length, width, pl.U(0.6, 0.75), paint, 2.0);
    const double cabin = length * pl.U(0.45, 0.6);
    pl.builder->AddShadowBox(base + up * 0.95 - forward * (length * 0.05), forward, cabin, width - 0.12,
                             pl.U(0.45, 0.55), glass, 1.0, pl.builder->AddSurface(roof));
  } else {
    const CarShape& c = kCarShapes[shape];
    const double body = c.body_height * pl.U(0.92, 1.08);
    pl.builder->AddShadowBox(base + up * 0.3, forward, length, width, body, paint, 2.0);
    const double cabin = length * c.cabin_fraction * pl.U(0.92, 1.05);
    pl.builder->AddShadowBox(base + up * (0.3 + body) - forward * (length * c.cabin_shift), forward, cabin,
                             width - 0.12, c.cabin_height * pl.U(0.9, 1.1), glass, 1.0, pl.builder->AddSurface(roof));
  }
  // Lights and number plates: small boxes on the front and the back.
  const Vec3 right = shadow.frame_right;
  Surface lamp = Textured(kTexCarPaint, {1.f, 1.f, 0.95f}, 0.f, 0.f);
  Surface tail = Textured(kTexCarPaint, {0.95f, 0.12f, 0.08f}, 0.f, 0.f);
  Surface plate = Textured(kTexCurb, {1.f, 1.f, 1.f}, 0.f, 0.f);
  for (int end = -1; end <= 1; end += 2) {
    const Vec3 face = base + forward * (end * (length / 2 + 0.02));
    for (int side = -1; side <= 1; side += 2)
      pl.builder->AddBox(face + right * (side * (width / 2 - 0.22)) + up * 0.72, forward, 0.06, 0.3, 0.12,
                         end > 0 ? lamp : tail, 0.3);
    pl.builder->AddBox(face + up * 0.45, forward, 0.04, 0.52, 0.12, plate, 0.52);
  }
  pl.builder->EndChunk();
  pl.scene->num_cars++;
}

void ParkedCars(Placement& pl, int side, double s_begin, double s_end) {
  const double sign = side == 0 ? -1.0 : 1.0;
  double s = s_begin + pl.U(0, 8);
  while (s < s_end) {
    if (pl.Merged(s)) {
      s += 2.0;
      continue;
    }
    const PathSample& p = pl.At(s);
    const bool parking = side == 0 ? p.profile.parking_left : p.profile.parking_right;
    if (!parking || !pl.Chance(pl.options.car_density)) {
      s += pl.U(5, 14);
      continue;
    }
    const int shape = pl.options.appearance.car_shapes ? static_cast<int>(pl.U(0, kNumCarShapes)) % kNumCarShapes : -1;
    const double length = shape < 0 ? pl.U(3.8, 4.8) : pl.U(kCarShapes[shape].min_length, kCarShapes[shape].max_length);
    const PathSample& mid = pl.At(s + length / 2);
    const Vec3 base = mid.road + mid.right * (sign * (pl.Edge(mid, side) - 1.15 - pl.U(0, 0.15)));
    const Vec3 forward = (pl.Chance(0.8) ? 1.0 : -1.0) * mid.tangent;
    if (pl.Free(base, forward, length, 1.9, Zone::kLane, 0.3, kMaxCarHeight)) AddCar(pl, base, forward, length, shape);
    s += length + pl.U(0.8, 6.0);
  }
}

void AddTree(Placement& pl, const Vec3& base, double trunk_height, double crown_h, double crown_v) {
  const Vec3 up = pl.builder->up();
  pl.builder->BeginChunk();
  Surface bark = Textured(kTexBark, pl.options.appearance.bark_tint, 0.f, 0.f);
  pl.builder->AddCylinder(base - up * 0.3, pl.U(0.12, 0.25), trunk_height + 0.3 + crown_v * 0.5, 8, bark, 1.0);
  Surface leaves = Textured(kTexLeaves, pl.options.appearance.leaves_tint * static_cast<float>(pl.U(0.85, 1.15)),
                            0.3f, 0.4f);
  pl.builder->AddBlob(base + up * (trunk_height + crown_v * 0.8), crown_h, crown_v, leaves, 1.5, pl.rng());
  pl.builder->EndChunk();
  pl.scene->num_trees++;
}

// Heights (m) of hedges and bushes (a bush: blob of radius <= 1.3 m lifted by half of it).
constexpr double kMinHedgeHeight = 1.0, kMaxHedgeHeight = 1.8;
constexpr double kMaxBushHeight = 2.0;

void Vegetation(Placement& pl, int side, double s_begin, double s_end) {
  const double sign = side == 0 ? -1.0 : 1.0;
  double s = s_begin + pl.U(0, 10);
  while (s < s_end) {
    if (pl.Merged(s)) {
      s += 2.0;
      continue;
    }
    const PathSample& p = pl.At(s);
    const double density = pl.options.tree_density * (p.profile.green ? 1.0 : 0.4);
    const double gap = p.profile.green ? pl.U(6, 14) : pl.U(10, 25);
    if (density <= 0) {
      s += 20;
      continue;
    }
    if (pl.Chance(std::min(1.0, density))) {
      // Street trees stand at the curb side of the sidewalk, verge trees further out.
      const double lateral = pl.Edge(p, side) + (p.profile.green ? pl.Walk(p, side) + pl.U(1.0, 3.0) : 0.7);
      const Vec3 base = p.road + p.right * (sign * lateral) + pl.builder->up() * pl.options.curb_height;
      const double crown_h = pl.U(1.4, 2.8), crown_v = pl.U(1.5, 2.8);
      const double trunk = pl.U(2.0, 3.5);
      const double tree_height = trunk + 2 * crown_v;
      if (!pl.path.InZone(base, Zone::kRoad, 0.3, tree_height) &&
          pl.Free(base, p.tangent, crown_h * 2, crown_h * 2, Zone::kLane, 0.5, tree_height))
        AddTree(pl, base, trunk, crown_h, crown_v);
    }
    if (p.profile.green && pl.Chance(0.5 * std::min(1.0, density))) {
      // Hedge or bush behind the verge.
      const double lateral = pl.Edge(p, side) + pl.Walk(p, side) + pl.U(0.5, 2.0);
      const Vec3 base = p.road + p.right * (sign * lateral) + pl.builder->up() * pl.options.curb_height;
      Surface leaves = Textured(kTexLeaves, pl.options.appearance.hedge_tint, 0.2f, 0.3f);
      if (pl.Chance(0.5)) {
        const double length = pl.U(4, 12);
        const Vec3 centre = base + p.right * (sign * 0.6);
        if (pl.Free(centre, p.tangent, length, 1.2, Zone::kStreet, 0.1, kMaxHedgeHeight)) {
          pl.builder->BeginChunk();
          pl.builder->AddShadowBox(centre - pl.builder->up() * 0.2, p.tangent, length, 1.2,
                                   pl.U(kMinHedgeHeight, kMaxHedgeHeight), leaves, 1.5);
          pl.builder->EndChunk();
        }
      } else if (!pl.path.InZone(base, Zone::kStreet, 0.5, kMaxBushHeight)) {
        pl.builder->BeginChunk();
        const double r = pl.U(0.6, 1.3);
        pl.builder->AddBlob(base + pl.builder->up() * (r * 0.5), r, r * 0.8, leaves, 1.5, pl.rng());
        pl.builder->EndChunk();
      }
    }
    s += gap;
  }
}

// Street lamp heights (m); signs are lower.
constexpr double kMinLampHeight = 6.0, kMaxLampHeight = 8.0;

void PolesAndSigns(Placement& pl, int side, double s_begin, double s_end) {
  const double sign = side == 0 ? -1.0 : 1.0;
  const Vec3 up = pl.builder->up();
  double s = s_begin + pl.U(0, 20);
  Surface metal = Textured(kTexMetal, {0.75f, 0.77f, 0.80f}, 0.2f, 0.2f);
  while (s < s_end) {
    if (pl.Merged(s)) {
      s += 2.0;
      continue;
    }
    const PathSample& p = pl.At(s);
    const double lateral = pl.Edge(p, side) + 0.45;
    const Vec3 base = p.road + p.right * (sign * lateral) + up * pl.options.curb_height;
    if (!pl.path.InZone(base, Zone::kRoad, 0.2, kMaxLampHeight)) {
      pl.builder->BeginChunk();
      if (pl.Chance(0.7)) {  // street lamp with an arm over the road
        const double h = pl.U(kMinLampHeight, kMaxLampHeight);
        pl.builder->AddCylinder(base, pl.U(0.08, 0.12), h, 8, metal, 1.0);
        const Vec3 arm_mid = base + up * (h - 0.1) - p.right * (sign * 0.8);
        pl.builder->AddBox(arm_mid, p.right, 1.8, 0.12, 0.1, metal, 1.0);
        pl.builder->AddBox(arm_mid - p.right * (sign * 0.9) - up * 0.15, p.tangent, 0.5, 0.3, 0.15, metal, 1.0);
      } else {  // traffic sign facing the traffic
        pl.builder->AddCylinder(base, 0.04, 2.6, 6, metal, 1.0);
        Surface plate = Textured(kTexSign, pl.Chance(0.5) ? Eigen::Vector3f(1.f, 0.95f, 0.95f)
                                                         : Eigen::Vector3f(0.85f, 0.9f, 1.f),
                                 0.f, 0.f);
        const Vec3 face_dir = -p.tangent;
        const Vec3 plate_base = base + up * 2.3 + face_dir * 0.06;
        pl.builder->AddBox(plate_base, face_dir, 0.03, 0.6, 0.6, plate, 0.6);
      }
      pl.builder->EndChunk();
      pl.scene->num_poles++;
    }
    s += pl.U(22, 40);
  }
}

}  // namespace

void PlaceStreetObjects(const StreetPath& path, const SceneOptions& options, uint64_t seed, SceneBuilder* builder,
                        Scene* scene) {
  const double s_begin = path.samples().front().s, s_end = path.samples().back().s;
  // One generator per object kind and side, so that changing e.g. the car
  // density does not move every building.
  for (int side = 0; side < 2; ++side) {
    auto make = [&](uint64_t kind) {
      return Placement{path, options, builder, scene, std::mt19937_64(seed * 1000003u + kind * 7u + side), {}};
    };
    Placement near = make(1), far = make(2), cars = make(3), green = make(4), poles = make(5);
    BuildingRow(near, side, false, s_begin, s_end);
    BuildingRow(far, side, true, s_begin, s_end);
    ParkedCars(cars, side, s_begin, s_end);
    Vegetation(green, side, s_begin, s_end);
    PolesAndSigns(poles, side, s_begin, s_end);
  }
}

}  // namespace dvso::sim
