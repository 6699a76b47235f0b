// Geometry and materials of the synthetic street: a list of planar triangles,
// each pointing at a Surface (texture mapping, colour, shading normal and an
// optional analytic overlay such as lane markings), grouped into chunks with a
// bounding sphere for view-frustum culling. The builder lays out the street
// (road, curbs, sidewalks, verges) and places buildings, parked cars, poles,
// signs, trees and hedges along a StreetPath.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "core/simulator_path.h"
#include "core/simulator_shadows.h"
#include "core/simulator_textures.h"

namespace dvso::sim {

enum class NormalMode : uint8_t {
  kFlat,      // the triangle's own plane normal
  kEllipsoid, // smooth normal of an ellipsoid (tree crowns, bushes)
  kCylinder,  // smooth radial normal of a vertical cylinder (poles, trunks)
};

enum class Overlay : uint8_t {
  kNone,
  kRoadMarkings,  // dashed centre line and solid edge lines, in street coordinates
  kPlinth,        // darker band at the bottom of a facade
  kShadow,        // soft contact shadow under a parked car
};

struct Surface {
  int texture = kTexAsphalt;            // detail texture (TextureId)
  Eigen::Vector3f tint{1.f, 1.f, 1.f};  // RGB albedo multiplier
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // texture origin (world)
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX(); // world -> u, in tiles per metre
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitZ(); // world -> v, in tiles per metre
  float macro_scale = 0.f;     // frequency of the macro stain texture relative to (u, v); 0 = off
  float macro_strength = 0.f;  // contrast of the macro stains (0..1)
  int max_taps = 1;            // anisotropic filter taps (ground surfaces seen at grazing angles)
  NormalMode normal_mode = NormalMode::kFlat;
  Eigen::Vector3d shape_center = Eigen::Vector3d::Zero();  // ellipsoid centre / cylinder axis point
  Eigen::Vector2d shape_radii{1.0, 1.0};                   // ellipsoid horizontal, vertical radius
  Overlay overlay = Overlay::kNone;
  // Overlay frame: street sample point, its tangent and right vectors, arc length.
  Eigen::Vector3d frame_origin = Eigen::Vector3d::Zero();
  Eigen::Vector3d frame_tangent = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d frame_right = Eigen::Vector3d::UnitX();
  double frame_s0 = 0;
  float overlay_a = 0, overlay_b = 0, overlay_c = 0;  // overlay parameters (see Overlay)
  uint8_t overlay_flags = 0;
  int caster_box = -1;        // shadow box this surface belongs to (not tested against itself)
  int caster_ellipsoid = -1;  // shadow ellipsoid this surface belongs to
};

struct Triangle {
  Eigen::Vector3d v[3];
  Eigen::Vector3d normal;  // unit plane normal, oriented outwards (lighting)
  double offset = 0;       // plane: normal . x = offset
  int surface = 0;
};

struct Chunk {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0;
  int begin = 0, end = 0;  // triangle range
};

// Look of a world: light, sky, material colours and textures, car shapes. The
// defaults are the original fixed look (renders do not change with them);
// RandomAppearance(seed) draws a varied one, so that a network trained on many
// seeds does not learn a single look.
struct Appearance {
  double sun_elevation_min_deg = 35;  // sun elevation drawn per seed in [min, max] (degrees)
  double sun_elevation_max_deg = 60;
  double sun_strength = 0.75;          // direct light on a surface facing the sun
  double sky_light = 0.55;             // ambient (sky) light on walls
  double sky_light_up = 0.2;           // extra ambient light on upward-facing surfaces
  Eigen::Vector3f light_colour{1.f, 1.f, 1.f};  // RGB multiplier of sun and sky light (warm / cold light)
  Eigen::Vector3f sky_horizon{0.93f, 0.94f, 0.96f};  // sky radiance at the horizon
  Eigen::Vector3f sky_zenith{0.55f, 0.68f, 0.90f};   // sky radiance at the zenith
  float cloud_threshold = 0.3f;       // cloud texture value where clouds start (lower = more clouds)
  int road_texture = kTexAsphalt;     // kTexAsphalt or kTexRoadConcrete
  Eigen::Vector3f road_tint{0.95f, 0.95f, 1.0f};
  Eigen::Vector3f paving_tint{0.92f, 0.88f, 0.84f};
  int grass_texture = kTexGrass;      // kTexGrass or kTexGrassDry
  Eigen::Vector3f grass_tint{0.55f, 0.75f, 0.40f};
  Eigen::Vector3f dirt_tint{0.80f, 0.72f, 0.60f};
  Eigen::Vector3f underlay_tint{0.65f, 0.62f, 0.55f};
  Eigen::Vector3f leaves_tint{0.62f, 0.80f, 0.42f};  // tree crowns (x 0.85..1.15 per tree)
  Eigen::Vector3f hedge_tint{0.55f, 0.72f, 0.38f};
  Eigen::Vector3f bark_tint{0.55f, 0.45f, 0.38f};
  int facade_styles = kNumFacadeStyles;  // styles drawn from: 4 = the original, 6 adds siding and glass
  float facade_free_colour = 0.f;     // probability that a building's colour is any hue (else the palette)
  bool car_shapes = false;            // sedans, hatchbacks, estates, SUVs and vans instead of one sedan shape
  float car_detail = 0.f;             // probability that a car's paint shows reflections, dirt and handles
  bool varied = false;                // drawn by RandomAppearance (recorded in simulation.yaml)
};

// The varied look's share of cars with detailed paint is drawn in [kVariedCarDetailMin, 1]: some plain cars stay.
constexpr float kVariedCarDetailMin = 0.3f;

// A varied look drawn from the seed: sun elevation 12-70 degrees, sunny to
// overcast light, warm / cold light colour, sky colour and clouds, asphalt or
// concrete road, material tints, six facade styles with free colours, car shapes.
Appearance RandomAppearance(uint64_t seed);

struct Scene {
  std::vector<Surface> surfaces;
  std::vector<Triangle> triangles;
  std::vector<Chunk> chunks;
  Eigen::Vector3d down = Eigen::Vector3d::UnitY();     // world down
  Eigen::Vector3d horizontal_a = Eigen::Vector3d::UnitX();  // horizontal basis (ground textures)
  Eigen::Vector3d horizontal_b = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d to_sun = Eigen::Vector3d(0.3, -0.8, 0.5).normalized();  // unit, towards the sun
  Appearance appearance;  // light and sky used by the shader
  int num_buildings = 0, num_cars = 0, num_poles = 0, num_trees = 0;
  // Occluders collected while placing objects, then indexed in `shadows`.
  std::vector<ShadowBox> shadow_boxes;
  std::vector<ShadowEllipsoid> shadow_ellipsoids;
  ShadowCasters shadows;
};

struct SceneOptions {
  double building_density = 0.8;  // fraction of street length lined by near buildings (0..1)
  double car_density = 0.6;       // fraction of parking lanes occupied by cars (0..1)
  double tree_density = 0.5;      // relative number of trees, hedges and bushes (0..)
  double curb_height = 0.12;      // sidewalk height above the road (m)
  bool shadows = true;            // sun shadows cast by buildings, cars, hedges and trees
  // The invented streets before the first and after the last pose build nothing where they run over the driven
  // path (StreetPath::DropExtensionsOverThePath); false = simulator world versions 1-2 (core/simulator.h).
  bool extensions_yield = true;
  Appearance appearance;          // light, colours, textures and car shapes
};

// Builds the whole street along the path. Assigns each sample's StreetProfile
// (hence the non-const path). Deterministic for a given path and seed.
Scene BuildStreetScene(StreetPath& path, const SceneOptions& options, uint64_t seed);

// --- primitive helpers shared by the scene files (simulator_scene.cpp,
// simulator_objects.cpp) ---
class SceneBuilder {
 public:
  SceneBuilder(Scene* scene, const Eigen::Vector3d& down) : scene_(scene), down_(down) {}
  const Eigen::Vector3d& down() const { return down_; }
  Eigen::Vector3d up() const { return -down_; }
  int AddSurface(const Surface& surface);
  void BeginChunk();
  void EndChunk();
  // Planar-ish quad a-b-c-d (two triangles a-b-c, a-c-d); normals oriented
  // towards `outward`.
  void AddQuad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
               const Eigen::Vector3d& d, const Eigen::Vector3d& outward, int surface);
  void AddTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                   const Eigen::Vector3d& outward, int surface);
  // Oriented box standing on `base` (centre of its bottom face), with
  // horizontal unit `forward`, length along forward, width, height. Every
  // face gets a copy of `surface` with u along the face's horizontal edge and
  // v upwards (scaled by 1 / tile_metres); `top` replaces the top face's
  // surface when >= 0.
  void AddBox(const Eigen::Vector3d& base, const Eigen::Vector3d& forward, double length, double width,
              double height, Surface surface, double tile_metres, int top = -1);
  // The same box registered as a shadow caster (its faces are not tested against it).
  void AddShadowBox(const Eigen::Vector3d& base, const Eigen::Vector3d& forward, double length, double width,
                    double height, Surface surface, double tile_metres, int top = -1);
  // Vertical prism approximating a cylinder, smooth-shaded.
  void AddCylinder(const Eigen::Vector3d& base, double radius, double height, int sides, Surface surface,
                   double tile_metres);
  // Lumpy ellipsoid (subdivided icosahedron with radial noise), smooth-shaded.
  void AddBlob(const Eigen::Vector3d& center, double radius_h, double radius_v, Surface surface,
               double tile_metres, uint64_t seed);

 private:
  Scene* scene_;
  Eigen::Vector3d down_;
  int chunk_begin_ = 0;
};

// Places buildings, cars, poles, signs and vegetation (simulator_objects.cpp).
void PlaceStreetObjects(const StreetPath& path, const SceneOptions& options, uint64_t seed,
                        SceneBuilder* builder, Scene* scene);

}  // namespace dvso::sim
