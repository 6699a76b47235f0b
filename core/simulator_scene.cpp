#include "core/simulator_scene.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace dvso::sim {

// ------------------------------------------------------------ primitives ---
int SceneBuilder::AddSurface(const Surface& surface) {
  scene_->surfaces.push_back(surface);
  return static_cast<int>(scene_->surfaces.size()) - 1;
}

void SceneBuilder::BeginChunk() { chunk_begin_ = static_cast<int>(scene_->triangles.size()); }

void SceneBuilder::EndChunk() {
  const int end = static_cast<int>(scene_->triangles.size());
  if (end == chunk_begin_) return;
  Eigen::Vector3d lo = scene_->triangles[chunk_begin_].v[0], hi = lo;
  for (int t = chunk_begin_; t < end; ++t)
    for (const auto& v : scene_->triangles[t].v) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
  Chunk chunk;
  chunk.center = 0.5 * (lo + hi);
  chunk.radius = 0.5 * (hi - lo).norm() + 1e-3;
  chunk.begin = chunk_begin_;
  chunk.end = end;
  scene_->chunks.push_back(chunk);
  chunk_begin_ = end;
}

void SceneBuilder::AddTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                               const Eigen::Vector3d& outward, int surface) {
  Eigen::Vector3d n = (b - a).cross(c - a);
  if (n.norm() < 1e-9) return;  // degenerate
  n.normalize();
  if (n.dot(outward) < 0) n = -n;
  Triangle tri;
  tri.v[0] = a;
  tri.v[1] = b;
  tri.v[2] = c;
  tri.normal = n;
  tri.offset = n.dot(a);
  tri.surface = surface;
  scene_->triangles.push_back(tri);
}

void SceneBuilder::AddQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                           const Eigen::Vector3d& d, const Eigen::Vector3d& outward, int surface) {
  AddTriangle(a, b, c, outward, surface);
  AddTriangle(a, c, d, outward, surface);
}

void SceneBuilder::AddBox(const Eigen::Vector3d& base, const Eigen::Vector3d& forward, double length,
                          double width, double height, Surface surface, double tile_metres, int top) {
  const Eigen::Vector3d f = forward.normalized() * (0.5 * length);
  const Eigen::Vector3d r = down_.cross(forward).normalized() * (0.5 * width);
  const Eigen::Vector3d h = up() * height;
  // Bottom corners counter-clockwise seen from above: rear-left, rear-right, front-right, front-left.
  const Eigen::Vector3d c[4] = {base - f - r, base - f + r, base + f + r, base + f - r};
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d& p = c[i];
    const Eigen::Vector3d& q = c[(i + 1) % 4];
    const Eigen::Vector3d mid = 0.5 * (p + q);
    Surface face = surface;
    face.origin = p;
    face.axis_u = (q - p).normalized() / tile_metres;
    face.axis_v = up() / tile_metres;
    AddQuad(p, q, q + h, p + h, mid - base, AddSurface(face));
  }
  int top_surface = top;
  if (top_surface < 0) {
    Surface face = surface;
    face.origin = c[0];
    face.axis_u = forward.normalized() / tile_metres;
    face.axis_v = r.normalized() / tile_metres;
    top_surface = AddSurface(face);
  }
  AddQuad(c[0] + h, c[1] + h, c[2] + h, c[3] + h, up(), top_surface);
}

void SceneBuilder::AddShadowBox(const Eigen::Vector3d& base, const Eigen::Vector3d& forward, double length,
                                double width, double height, Surface surface, double tile_metres, int top) {
  ShadowBox box;
  box.axis[0] = forward.normalized();
  box.axis[1] = down_.cross(box.axis[0]).normalized();
  box.axis[2] = up();
  box.center = base + up() * (0.5 * height);
  box.half[0] = 0.5 * length;
  box.half[1] = 0.5 * width;
  box.half[2] = 0.5 * height;
  surface.caster_box = static_cast<int>(scene_->shadow_boxes.size());
  scene_->shadow_boxes.push_back(box);
  if (top >= 0) scene_->surfaces[top].caster_box = surface.caster_box;
  AddBox(base, forward, length, width, height, surface, tile_metres, top);
}

void SceneBuilder::AddCylinder(const Eigen::Vector3d& base, double radius, double height, int sides,
                               Surface surface, double tile_metres) {
  const Eigen::Vector3d a = down_.unitOrthogonal(), b = down_.cross(a);
  const Eigen::Vector3d h = up() * height;
  surface.normal_mode = NormalMode::kCylinder;
  surface.shape_center = base;
  const double facet = 2 * radius * std::sin(M_PI / sides);
  for (int i = 0; i < sides; ++i) {
    const double a0 = 2 * M_PI * i / sides, a1 = 2 * M_PI * (i + 1) / sides;
    const Eigen::Vector3d p = base + radius * (std::cos(a0) * a + std::sin(a0) * b);
    const Eigen::Vector3d q = base + radius * (std::cos(a1) * a + std::sin(a1) * b);
    Surface face = surface;
    face.axis_u = (q - p).normalized() / tile_metres;
    face.origin = p - (q - p).normalized() * (i * facet);  // u continuous around the pole
    face.axis_v = up() / tile_metres;
    AddQuad(p, q, q + h, p + h, 0.5 * (p + q) - base, AddSurface(face));
  }
}

void SceneBuilder::AddBlob(const Eigen::Vector3d& center, double radius_h, double radius_v, Surface surface,
                           double tile_metres, uint64_t seed) {
  // Icosahedron, subdivided once (80 faces).
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (auto& p : v) p.normalize();
  std::vector<Eigen::Vector3i> f2;
  for (const auto& tri : f) {
    int m[3];
    for (int e = 0; e < 3; ++e) {
      v.push_back((v[tri[e]] + v[tri[(e + 1) % 3]]).normalized());
      m[e] = static_cast<int>(v.size()) - 1;
    }
    f2.push_back({tri[0], m[0], m[2]});
    f2.push_back({tri[1], m[1], m[0]});
    f2.push_back({tri[2], m[2], m[1]});
    f2.push_back({m[0], m[1], m[2]});
  }
  // Radial noise per direction (hash of the rounded direction, so that
  // duplicated edge midpoints move together and the surface stays closed).
  auto bump = [&](const Eigen::Vector3d& d) {
    uint64_t h = seed * 0x9E3779B97F4A7C15ull;
    for (int k = 0; k < 3; ++k) {
      h ^= static_cast<uint64_t>(std::llround(d[k] * 1000) + 4096) + 0x9E3779B97F4A7C15ull + (h << 6) + (h >> 2);
      h = (h ^ (h >> 31)) * 0xBF58476D1CE4E5B9ull;
    }
    return 0.85 + 0.3 * static_cast<double>(h >> 11) / 9007199254740992.0;
  };
  const Eigen::Vector3d a = down_.unitOrthogonal(), b = down_.cross(a);
  auto place = [&](const Eigen::Vector3d& d) {
    const double k = bump(d);
    return Eigen::Vector3d(center + k * (radius_h * (d.x() * a + d.z() * b) + radius_v * d.y() * down_));
  };
  surface.normal_mode = NormalMode::kEllipsoid;
  surface.shape_center = center;
  // The lumpy blob casts the shadow of its mean ellipsoid.
  ShadowEllipsoid shadow;
  shadow.center = center;
  shadow.radius_h = radius_h;
  shadow.radius_v = radius_v;
  surface.caster_ellipsoid = static_cast<int>(scene_->shadow_ellipsoids.size());
  scene_->shadow_ellipsoids.push_back(shadow);
  surface.shape_radii = {radius_h, radius_v};
  for (const auto& tri : f2) {
    const Eigen::Vector3d p0 = place(v[tri[0]]), p1 = place(v[tri[1]]), p2 = place(v[tri[2]]);
    Eigen::Vector3d n = (p1 - p0).cross(p2 - p0);
    if (n.norm() < 1e-12) continue;
    n.normalize();
    Surface face = surface;
    Eigen::Vector3d au = n.cross(down_);
    if (au.norm() < 1e-3) au = a;
    au.normalize();
    face.axis_u = au / tile_metres;
    face.axis_v = n.cross(au).normalized() / tile_metres;
    face.origin = center;
    AddTriangle(p0, p1, p2, (p0 + p1 + p2) / 3.0 - center, AddSurface(face));
  }
}

// --------------------------------------------------------------- street ----
namespace {

StreetProfile RandomProfile(std::mt19937_64& rng, int section) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  StreetProfile p;
  p.section = section;
  const bool one_way = u(rng) < 0.2;
  p.parking_left = u(rng) < 0.45;
  p.parking_right = u(rng) < 0.6;
  p.right_edge = 1.7 + 0.6 * u(rng) + (p.parking_right ? 2.3 : 0.0);
  p.left_edge = -(one_way ? 1.8 + 0.6 * u(rng) : 5.0 + 0.8 * u(rng)) - (p.parking_left ? 2.3 : 0.0);
  p.sidewalk_left = 1.5 + 2.5 * u(rng);
  p.sidewalk_right = 1.5 + 2.5 * u(rng);
  p.green = u(rng) < 0.4;
  return p;
}

// Street sections of 60-200 m with their own cross-section, blended over 10 m.
void AssignProfiles(StreetPath& path, uint64_t seed) {
  auto& samples = path.mutable_samples();
  std::mt19937_64 rng(seed * 31337u + 5u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> starts = {samples.front().s};
  std::vector<StreetProfile> profiles = {RandomProfile(rng, 0)};
  while (starts.back() < samples.back().s) {
    starts.push_back(starts.back() + 60 + 140 * u(rng));
    profiles.push_back(RandomProfile(rng, static_cast<int>(profiles.size())));
  }
  const double blend = 10.0;
  size_t k = 0;
  for (auto& sample : samples) {
    while (k + 1 < starts.size() && sample.s >= starts[k + 1]) ++k;
    StreetProfile p = profiles[k];
    const double into = sample.s - starts[k];
    if (k > 0 && into < blend) {
      const StreetProfile& q = profiles[k - 1];
      const double w = into / blend;
      p.left_edge = q.left_edge + w * (p.left_edge - q.left_edge);
      p.right_edge = q.right_edge + w * (p.right_edge - q.right_edge);
      p.sidewalk_left = q.sidewalk_left + w * (p.sidewalk_left - q.sidewalk_left);
      p.sidewalk_right = q.sidewalk_right + w * (p.sidewalk_right - q.sidewalk_right);
      p.parking_left = p.parking_left && q.parking_left;
      p.parking_right = p.parking_right && q.parking_right;
    }
    sample.profile = p;
  }
}

Surface GroundSurface(const Scene& scene, int texture, double tile_metres, const Eigen::Vector3f& tint,
                      int taps) {
  // World-anchored horizontal mapping: overlapping ground pieces (loops,
  // crossings, inner sides of turns) show identical texture.
  Surface s;
  s.texture = texture;
  s.tint = tint;
  s.axis_u = scene.horizontal_a / tile_metres;
  s.axis_v = scene.horizontal_b / tile_metres;
  s.macro_scale = static_cast<float>(tile_metres / 37.0);
  s.macro_strength = 0.35f;
  s.max_taps = taps;
  return s;
}

// How far (m) the ground of one side can reach from `from` before it enters
// another street's `zone`.
double FreeExtent(const StreetPath& path, int j, double side, double from, double limit, double step, Zone zone) {
  const PathSample& p = path.samples()[j];
  const int n = static_cast<int>(path.samples().size());
  double reach = from;
  for (double l = from + step; l <= limit + 1e-9; l += step) {
    const Eigen::Vector3d q = p.road + p.right * (side * l);
    if (path.InZoneOfOtherSamples(q, zone, 0.3, std::max(0, j - 2), std::min(n, j + 3))) break;
    reach = l;
  }
  return reach;
}

void BuildStreetSurfaces(const StreetPath& path, const SceneOptions& options, SceneBuilder* builder,
                         Scene* scene) {
  const auto& samples = path.samples();
  const int n = static_cast<int>(samples.size());
  const Eigen::Vector3d up = builder->up();
  const Eigen::Vector3d curb = up * options.curb_height;
  // Per sample and side: verge reach, underlay reach, junction flag.
  std::vector<double> verge[2], under[2];
  std::vector<char> junction[2];
  for (int side = 0; side < 2; ++side) {
    verge[side].resize(n);
    under[side].resize(n);
    junction[side].resize(n);
    const double sign = side == 0 ? -1.0 : 1.0;
    for (int j = 0; j < n; ++j) {
      const StreetProfile& p = samples[j].profile;
      const double edge = side == 0 ? -p.left_edge : p.right_edge;
      const double walk = side == 0 ? p.sidewalk_left : p.sidewalk_right;
      const int lo = std::max(0, j - 2), hi = std::min(n, j + 3);
      const Eigen::Vector3d outer = samples[j].road + samples[j].right * (sign * (edge + walk));
      const Eigen::Vector3d inner = samples[j].road + samples[j].right * (sign * (edge + 0.3));
      junction[side][j] = path.InZoneOfOtherSamples(outer, Zone::kRoad, 0.3, lo, hi) ||
                           path.InZoneOfOtherSamples(inner, Zone::kRoad, 0.3, lo, hi);
      verge[side][j] = FreeExtent(path, j, sign, edge + walk, 40.0, 2.0, Zone::kStreet);
      under[side][j] = std::max(verge[side][j], FreeExtent(path, j, sign, edge, 70.0, 4.0, Zone::kRoad));
    }
  }
  const Appearance& look = options.appearance;
  const Surface asphalt = GroundSurface(*scene, look.road_texture, 2.5, look.road_tint, 4);
  const int plain_asphalt = builder->AddSurface(asphalt);
  const int paving = builder->AddSurface(GroundSurface(*scene, kTexPaving, 2.0, look.paving_tint, 4));
  const int grass = builder->AddSurface(GroundSurface(*scene, look.grass_texture, 2.0, look.grass_tint, 3));
  const int dirt = builder->AddSurface(GroundSurface(*scene, kTexDirt, 3.0, look.dirt_tint, 3));
  const int underlay = builder->AddSurface(GroundSurface(*scene, kTexDirt, 3.0, look.underlay_tint, 2));

  for (int j = 0; j + 1 < n; ++j) {
    const PathSample& a = samples[j];
    const PathSample& b = samples[j + 1];
    if (a.merged_into >= 0 && b.merged_into >= 0) continue;  // a revisit: the earlier street is reused
    auto at = [](const PathSample& s, double lateral) { return Eigen::Vector3d(s.road + s.right * lateral); };
    builder->BeginChunk();
    // Road with analytic markings in this segment's street coordinates.
    Surface road = asphalt;
    road.overlay = Overlay::kRoadMarkings;
    road.frame_origin = a.road;
    road.frame_tangent = (b.road - a.road - (b.road - a.road).dot(builder->down()) * builder->down()).normalized();
    road.frame_right = builder->down().cross(road.frame_tangent).normalized();
    road.frame_s0 = a.s;
    const StreetProfile& pa = a.profile;
    auto junction_at = [&](int k) { return k >= 0 && k < n && (junction[0][k] || junction[1][k]); };
    const bool any_junction = junction_at(j) || junction_at(j + 1);
    // Zebra crossings on the 4 m of road just before and after a crossing street.
    const bool zebra = !any_junction && (junction_at(j + 2) || junction_at(j + 3) || junction_at(j - 1) || junction_at(j - 2));
    road.overlay_a = static_cast<float>(pa.left_edge);
    road.overlay_b = static_cast<float>(pa.right_edge);
    road.overlay_flags = static_cast<uint8_t>((pa.left_edge < -4.0 && !any_junction ? 1 : 0) |
                                              (!pa.parking_left && !any_junction ? 2 : 0) |
                                              (!pa.parking_right && !any_junction ? 4 : 0) | (zebra ? 8 : 0));
    const int road_surface = builder->AddSurface(road);
    builder->AddQuad(at(a, a.profile.left_edge), at(a, a.profile.right_edge), at(b, b.profile.right_edge),
                     at(b, b.profile.left_edge), up, road_surface);
    for (int side = 0; side < 2; ++side) {
      const double sign = side == 0 ? -1.0 : 1.0;
      auto edge = [&](const PathSample& s) { return side == 0 ? -s.profile.left_edge : s.profile.right_edge; };
      auto walk = [&](const PathSample& s) { return side == 0 ? s.profile.sidewalk_left : s.profile.sidewalk_right; };
      const double ea = edge(a), eb = edge(b);
      const double wa = ea + walk(a), wb = eb + walk(b);
      const double va = verge[side][j], vb = verge[side][j + 1];
      // Underlay: low dirt ground that closes every hole below the horizon.
      const Eigen::Vector3d sink = -0.3 * up;
      // It starts under the verge's outer edge (overdraw elsewhere would be wasted).
      const double ua = junction[side][j] ? ea : std::max(ea, va - 1.0);
      const double ub = junction[side][j + 1] ? eb : std::max(eb, vb - 1.0);
      builder->AddQuad(at(a, sign * ua) + sink, at(a, sign * std::max(ua, under[side][j])) + sink,
                       at(b, sign * std::max(ub, under[side][j + 1])) + sink, at(b, sign * ub) + sink, up, underlay);
      if (junction[side][j] || junction[side][j + 1]) {
        // Another street crosses here: asphalt instead of curb and sidewalk.
        builder->AddQuad(at(a, sign * ea), at(a, sign * (wa + 2)), at(b, sign * (wb + 2)), at(b, sign * eb), up,
                         plain_asphalt);
        continue;
      }
      Surface curb_face;
      curb_face.texture = kTexCurb;
      curb_face.tint = {0.9f, 0.9f, 0.9f};
      curb_face.axis_u = road.frame_tangent / 1.0;
      curb_face.origin = a.road - road.frame_tangent * a.s;
      curb_face.axis_v = up / 1.0;
      curb_face.macro_scale = 0.05f;
      curb_face.macro_strength = 0.3f;
      builder->AddQuad(at(a, sign * ea), at(b, sign * eb), at(b, sign * eb) + curb, at(a, sign * ea) + curb,
                       -sign * a.right, builder->AddSurface(curb_face));
      builder->AddQuad(at(a, sign * ea) + curb, at(a, sign * wa) + curb, at(b, sign * wb) + curb,
                       at(b, sign * eb) + curb, up, paving);
      if (va > wa + 0.1 || vb > wb + 0.1) {
        const int verge_surface = a.profile.green ? grass : (a.profile.section % 3 == 0 ? paving : dirt);
        builder->AddQuad(at(a, sign * wa) + curb, at(a, sign * std::max(va, wa)) + curb,
                         at(b, sign * std::max(vb, wb)) + curb, at(b, sign * wb) + curb, up, verge_surface);
      }
    }
    builder->EndChunk();
  }
}

}  // namespace

Appearance RandomAppearance(uint64_t seed) {
  std::mt19937_64 rng(seed * 0x2545F4914F6CDD1Dull + 0x9E37u);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto U = [&](double lo, double hi) { return static_cast<float>(lo + (hi - lo) * unit(rng)); };
  // Tint: base colour with a brightness factor and a small per-channel change.
  auto Tint = [&](const Eigen::Vector3f& base, double lo, double hi, double hue) {
    const float v = U(lo, hi);
    Eigen::Vector3f t(base.x() * (1 + U(-hue, hue)), base.y() * (1 + U(-hue, hue)), base.z() * (1 + U(-hue, hue)));
    return Eigen::Vector3f((t * v).cwiseMin(1.f).cwiseMax(0.02f));
  };
  Appearance a;
  a.varied = true;
  const double overcast = unit(rng) < 0.3 ? U(0.6, 1.0) : U(0.0, 0.4);  // 0 = clear sky, 1 = overcast
  a.sun_elevation_min_deg = 12;
  a.sun_elevation_max_deg = 70;
  a.sun_strength = (1 - 0.85 * overcast) * U(0.65, 1.0);
  a.sky_light = 0.45 + 0.3 * overcast + U(-0.08, 0.08);
  a.sky_light_up = U(0.1, 0.3);
  const float warmth = U(-0.12, 0.15);  // > 0: warm (evening) light, < 0: cold
  a.light_colour = Eigen::Vector3f(1 + warmth, 1.f, 1 - warmth);
  const Eigen::Vector3f grey_sky(0.82f, 0.83f, 0.85f);
  const float ov = static_cast<float>(overcast);
  a.sky_horizon = Eigen::Vector3f(0.93f, 0.94f, 0.96f) * (1 - ov) + grey_sky * ov;
  a.sky_zenith = (Eigen::Vector3f(U(0.40, 0.65), U(0.55, 0.75), U(0.85, 0.97)) * (1 - ov) + grey_sky * 0.9f * ov);
  a.cloud_threshold = static_cast<float>(U(0.1, 0.6) - 0.3 * overcast);
  a.road_texture = unit(rng) < 0.3 ? kTexRoadConcrete : kTexAsphalt;
  a.road_tint = Tint(a.road_texture == kTexAsphalt ? Eigen::Vector3f(0.95f, 0.95f, 1.0f) : Eigen::Vector3f(0.9f, 0.9f, 0.88f),
                     0.6, 1.25, 0.06);
  a.paving_tint = Tint({0.92f, 0.88f, 0.84f}, 0.6, 1.1, 0.12);
  a.grass_texture = unit(rng) < 0.35 ? kTexGrassDry : kTexGrass;
  // Grass and leaves from fresh green to dry yellow / autumn orange.
  const float dry = U(0.0, 1.0) * (a.grass_texture == kTexGrassDry ? 1.f : 0.4f);
  a.grass_tint = Tint(Eigen::Vector3f(0.55f + 0.25f * dry, 0.75f - 0.05f * dry, 0.40f - 0.1f * dry), 0.7, 1.15, 0.08);
  const float autumn = unit(rng) < 0.25 ? U(0.3, 1.0) : 0.f;
  a.leaves_tint = Tint(Eigen::Vector3f(0.62f + 0.35f * autumn, 0.80f - 0.15f * autumn, 0.42f - 0.15f * autumn), 0.6, 1.15, 0.1);
  a.hedge_tint = Tint({0.55f, 0.72f, 0.38f}, 0.6, 1.15, 0.1);
  a.dirt_tint = Tint({0.80f, 0.72f, 0.60f}, 0.7, 1.15, 0.1);
  a.underlay_tint = Tint({0.65f, 0.62f, 0.55f}, 0.7, 1.15, 0.1);
  a.bark_tint = Tint({0.55f, 0.45f, 0.38f}, 0.6, 1.3, 0.1);
  a.facade_styles = kNumFacadeStyles + kNumExtraFacadeStyles;
  a.facade_free_colour = U(0.2, 0.7);
  a.car_shapes = true;
  // Drawn last, so every draw above stays what it was before session 36.
  a.car_detail = U(kVariedCarDetailMin, 1.0);
  return a;
}

Scene BuildStreetScene(StreetPath& path, const SceneOptions& options, uint64_t seed) {
  Require(options.building_density >= 0 && options.building_density <= 1, "building density must be in [0, 1]");
  Require(options.car_density >= 0 && options.car_density <= 1, "car density must be in [0, 1]");
  Require(options.tree_density >= 0, "tree density must be >= 0");
  Require(options.curb_height >= 0 && options.curb_height < 0.5, "curb height must be in [0, 0.5) m");
  Scene scene;
  scene.down = path.down();
  scene.horizontal_a = scene.down.unitOrthogonal();
  scene.horizontal_b = scene.down.cross(scene.horizontal_a);
  scene.appearance = options.appearance;
  // Sun: elevation in the appearance's range (35-60 degrees by default), azimuth from the seed.
  std::mt19937_64 rng(seed * 101u + 3u);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Appearance& look = options.appearance;
  const double azimuth = 2 * M_PI * u(rng);
  const double elevation =
      (look.sun_elevation_min_deg + (look.sun_elevation_max_deg - look.sun_elevation_min_deg) * u(rng)) * M_PI / 180;
  scene.to_sun = (std::cos(elevation) * (std::cos(azimuth) * scene.horizontal_a + std::sin(azimuth) * scene.horizontal_b) -
                  std::sin(elevation) * scene.down)
                     .normalized();
  AssignProfiles(path, seed);
  if (options.extensions_yield) path.DropExtensionsOverThePath(kExtensionYieldRadius, kRevisitMinArcGap);
  path.MergeRevisits(kRevisitMergeRadius, kRevisitMinArcGap);
  SceneBuilder builder(&scene, scene.down);
  BuildStreetSurfaces(path, options, &builder, &scene);
  PlaceStreetObjects(path, options, seed, &builder, &scene);
  if (options.shadows)
    scene.shadows = ShadowCasters(scene.shadow_boxes, scene.shadow_ellipsoids, scene.down, scene.to_sun);
  return scene;
}

}  // namespace dvso::sim
