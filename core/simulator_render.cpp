#include "core/simulator_render.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>
#include <vector>

#include "core/error.h"
#include "core/luma.h"
#include "core/vignette.h"

namespace dvso::sim {
namespace {

constexpr int kTileRows = 8;
constexpr double kNearPlane = 0.05;  // metres

// A triangle after clipping and projection: three edge functions
// E(x, y) = a x + b y + c (>= 0 inside), inverse depth 1/z = p x + q y + r.
struct ScreenTriangle {
  double ea[3], eb[3], ec[3];
  bool include_zero[3];  // top-left rule: pixels exactly on a shared edge go to one triangle
  double ip, iq, ir;
  int x0, x1, y0, y1;  // inclusive pixel bounding box
  int triangle;
};

// splitmix64: per-pixel noise that is independent of thread scheduling.
inline uint64_t Mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
// Approximately standard normal value from 64 random bits (sum of four
// uniforms, Irwin-Hall; variance matched).
inline float GaussFromBits(uint64_t bits) {
  const float sum = static_cast<float>((bits & 0xffff) + ((bits >> 16) & 0xffff) + ((bits >> 32) & 0xffff) +
                                       ((bits >> 48) & 0xffff)) *
                    (1.0f / 65536.0f);
  return (sum - 2.0f) * 1.7320508f;
}

inline uint8_t Quantise(float v) { return static_cast<uint8_t>(std::clamp(v + 0.5f, 0.f, 255.f)); }

// Runs work(tile) for tiles 0..num_tiles-1 on num_threads threads (the
// caller's included); tiles are taken from a shared counter.
template <typename Work>
void ParallelTiles(int num_tiles, int num_threads, const Work& work) {
  std::atomic<int> next{0};
  auto worker = [&]() {
    for (int tile = next++; tile < num_tiles; tile = next++) work(tile);
  };
  std::vector<std::thread> threads;
  for (int t = 1; t < num_threads; ++t) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
}

}  // namespace

Renderer::Renderer(const Scene& scene, const TextureBank& textures, const PinholeCamera& camera, int num_threads,
                   double max_distance, bool edge_antialiasing, bool uncovered_subsamples_see_sky)
    : scene_(scene),
      shader_(scene, textures),
      camera_(camera),
      num_threads_(num_threads),
      max_distance_(max_distance),
      edge_antialiasing_(edge_antialiasing),
      uncovered_subsamples_see_sky_(uncovered_subsamples_see_sky) {
  camera_.Check();
  Require(num_threads >= 1, "number of render threads must be >= 1");
  Require(max_distance > 1.0, "render distance must be > 1 m");
}

RenderedView Renderer::Render(const Eigen::Isometry3d& T_world_camera, const Photometric& photometric,
                              bool with_color) const {
  const int width = camera_.width, height = camera_.height;
  const double fx = camera_.fx, fy = camera_.fy, cx = camera_.cx, cy = camera_.cy;
  const Eigen::Matrix3d R = T_world_camera.linear();
  const Eigen::Matrix3d Rt = R.transpose();
  const Eigen::Vector3d C = T_world_camera.translation();

  // ---- 1. Cull chunks against the view frustum, clip and project triangles.
  Eigen::Vector3d side_planes[4] = {Eigen::Vector3d(1, 0, (cx + 0.5) / fx), Eigen::Vector3d(-1, 0, (width - 0.5 - cx) / fx),
                                    Eigen::Vector3d(0, 1, (cy + 0.5) / fy), Eigen::Vector3d(0, -1, (height - 0.5 - cy) / fy)};
  for (auto& p : side_planes) p.normalize();
  std::vector<ScreenTriangle> screen;
  screen.reserve(8192);
  for (const Chunk& chunk : scene_.chunks) {
    const Eigen::Vector3d c = Rt * (chunk.center - C);
    if (c.z() + chunk.radius < kNearPlane || c.z() - chunk.radius > max_distance_) continue;
    bool outside = false;
    for (const auto& p : side_planes) outside |= p.dot(c) < -chunk.radius;
    if (outside) continue;
    for (int t = chunk.begin; t < chunk.end; ++t) {
      const Triangle& tri = scene_.triangles[t];
      Eigen::Vector3d v[3];
      for (int k = 0; k < 3; ++k) v[k] = Rt * (tri.v[k] - C);
      // Every surface is the outside of a closed object or ground seen from
      // above, so back faces are hidden: skip them (halves the overdraw).
      if (tri.normal.dot(C - tri.v[0]) <= 0) continue;
      bool culled = false;
      for (const auto& p : side_planes) culled |= p.dot(v[0]) < 0 && p.dot(v[1]) < 0 && p.dot(v[2]) < 0;
      if (culled || (v[0].z() < kNearPlane && v[1].z() < kNearPlane && v[2].z() < kNearPlane)) continue;
      // Plane in camera coordinates: n_c . X = w_c; 1/z along pixel rays is affine in (x, y).
      const Eigen::Vector3d nc = Rt * tri.normal;
      const double wc = tri.offset - tri.normal.dot(C);
      if (std::abs(wc) < 1e-9) continue;  // seen exactly edge-on
      // Clip against the near plane (polygon of up to 4 vertices). Intersections
      // are computed from canonically ordered endpoints so that neighbouring
      // triangles produce bit-identical vertices (no cracks).
      Eigen::Vector3d poly[4];
      int count = 0;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& a = v[k];
        const Eigen::Vector3d& b = v[(k + 1) % 3];
        const bool ina = a.z() >= kNearPlane, inb = b.z() >= kNearPlane;
        if (ina) poly[count++] = a;
        if (ina != inb) {
          const bool a_first = std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
          const Eigen::Vector3d& p = a_first ? a : b;
          const Eigen::Vector3d& q = a_first ? b : a;
          const double s = (kNearPlane - p.z()) / (q.z() - p.z());
          poly[count++] = p + s * (q - p);
        }
      }
      if (count < 3) continue;
      double px[4], py[4];
      for (int k = 0; k < count; ++k) {
        px[k] = fx * poly[k].x() / poly[k].z() + cx;
        py[k] = fy * poly[k].y() / poly[k].z() + cy;
      }
      for (int k = 1; k + 1 < count; ++k) {
        const int idx[3] = {0, k, k + 1};
        ScreenTriangle st;
        double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
        for (int e = 0; e < 3; ++e) {
          const double x0 = px[idx[e]], y0 = py[idx[e]], x1 = px[idx[(e + 1) % 3]], y1 = py[idx[(e + 1) % 3]];
          st.ea[e] = y0 - y1;
          st.eb[e] = x1 - x0;
          st.ec[e] = x0 * y1 - x1 * y0;
          xmin = std::min(xmin, x0);
          xmax = std::max(xmax, x0);
          ymin = std::min(ymin, y0);
          ymax = std::max(ymax, y0);
        }
        const double area = st.ec[0] + st.ec[1] + st.ec[2];  // twice the signed area
        if (area == 0) continue;
        for (int e = 0; e < 3; ++e) {
          if (area < 0) {
            st.ea[e] = -st.ea[e];
            st.eb[e] = -st.eb[e];
            st.ec[e] = -st.ec[e];
          }
          st.include_zero[e] = st.ea[e] > 0 || (st.ea[e] == 0 && st.eb[e] > 0);
        }
        st.x0 = std::max(0, static_cast<int>(std::ceil(xmin)));
        st.x1 = std::min(width - 1, static_cast<int>(std::floor(xmax)));
        st.y0 = std::max(0, static_cast<int>(std::ceil(ymin)));
        st.y1 = std::min(height - 1, static_cast<int>(std::floor(ymax)));
        if (st.x0 > st.x1 || st.y0 > st.y1) continue;
        st.ip = nc.x() / (fx * wc);
        st.iq = nc.y() / (fy * wc);
        st.ir = (nc.z() - nc.x() * cx / fx - nc.y() * cy / fy) / wc;
        st.triangle = t;
        screen.push_back(st);
      }
    }
  }
  // Bin by tile rows.
  const int num_tiles = (height + kTileRows - 1) / kTileRows;
  std::vector<std::vector<int>> bins(num_tiles);
  for (int i = 0; i < static_cast<int>(screen.size()); ++i)
    for (int tile = screen[i].y0 / kTileRows; tile <= screen[i].y1 / kTileRows; ++tile) bins[tile].push_back(i);

  RenderedView out;
  out.grey.create(height, width, CV_8UC1);
  out.depth.create(height, width, CV_32FC1);
  if (with_color) out.color.create(height, width, CV_8UC3);
  const float min_inverse_depth = static_cast<float>(1.0 / max_distance_);
  const RadialPosition radial_position(camera_);
  const RadialVignette lens{{-photometric.vignetting_strength}};
  const double pixel_angle = 1.0 / std::max(fx, fy);
  const float scale = static_cast<float>(255.0 * photometric.gain);

  // ---- 2. Visibility buffer (nearest triangle per pixel), tiles in parallel.
  std::vector<float> zbuf(static_cast<size_t>(width) * height, min_inverse_depth);
  std::vector<int> ids(static_cast<size_t>(width) * height, -1);
  ParallelTiles(num_tiles, num_threads_, [&](int tile) {
    const int row0 = tile * kTileRows, row1 = std::min(height, row0 + kTileRows);
    for (int i : bins[tile]) {
      const ScreenTriangle& st = screen[i];
      for (int y = std::max(row0, st.y0); y <= std::min(row1 - 1, st.y1); ++y) {
        // Span of the row from the three edges. Pixels more than one pixel
        // inside the span are inside for sure; only the few pixels near its
        // ends need the exact (tie-breaking) edge test.
        double lo = st.x0, hi = st.x1;
        double span_lo = -1e300, span_hi = 1e300;
        bool empty = false;
        for (int e = 0; e < 3; ++e) {
          const double k = st.eb[e] * y + st.ec[e];
          if (st.ea[e] > 0) {
            span_lo = std::max(span_lo, -k / st.ea[e]);
          } else if (st.ea[e] < 0) {
            span_hi = std::min(span_hi, -k / st.ea[e]);
          } else if (k < 0 || (k == 0 && !st.include_zero[e])) {
            empty = true;  // the row lies outside a horizontal edge
          }
        }
        if (empty) continue;
        lo = std::max(lo, std::floor(std::max(span_lo, -1e9)) - 1);
        hi = std::min(hi, std::ceil(std::min(span_hi, 1e9)) + 1);
        if (lo > hi) continue;
        const double sure_lo = span_lo + 1.0, sure_hi = span_hi - 1.0;
        float* zrow = &zbuf[static_cast<size_t>(y) * width];
        int* idrow = &ids[static_cast<size_t>(y) * width];
        const double iz_row = st.iq * y + st.ir;
        for (int x = static_cast<int>(lo); x <= static_cast<int>(hi); ++x) {
          if (x <= sure_lo || x >= sure_hi) {
            bool inside = true;
            for (int e = 0; e < 3 && inside; ++e) {
              const double val = st.ea[e] * x + st.eb[e] * y + st.ec[e];
              inside = val > 0 || (val == 0 && st.include_zero[e]);
            }
            if (!inside) continue;
          }
          const float iz = static_cast<float>(st.ip * x + iz_row);
          if (iz > zrow[x]) {
            zrow[x] = iz;
            idrow[x] = i;
          }
        }
      }
    }
  });

  // ---- 3. Shading: each visible pixel once at its centre; pixels on a
  // depth or crease edge get 4 extra sub-samples (rotated grid) whose
  // radiance is averaged, so silhouettes are anti-aliased. GT depth stays
  // the exact value at the pixel centre.
  const Eigen::Vector3d rx = R.col(0) / fx, ry = R.col(1) / fy;
  // Radiance seen at image position (px, py) on screen triangle `id` (-1 = sky); z = depth.
  auto shade = [&](double px, double py, int id, double* z_out) -> Eigen::Vector3f {
    const Eigen::Vector3d ray = R.col(0) * ((px - cx) / fx) + R.col(1) * ((py - cy) / fy) + R.col(2);  // camera z = 1
    if (id < 0) {
      *z_out = 0;
      return shader_.Sky(ray.normalized(), pixel_angle);
    }
    const Triangle& tri = scene_.triangles[screen[id].triangle];
    const double n_ray = tri.normal.dot(ray);
    const double z = (tri.offset - tri.normal.dot(C)) / n_ray;  // exact depth of the plane hit
    // Hit point displacement per pixel (ray differentials on the plane).
    const Eigen::Vector3d dPdx = z * (rx - ray * (tri.normal.dot(rx) / n_ray));
    const Eigen::Vector3d dPdy = z * (ry - ray * (tri.normal.dot(ry) / n_ray));
    *z_out = z;
    return shader_.Surface(tri, C + z * ray, dPdx, dPdy);
  };
  auto is_edge = [&](int x, int y) {
    const int a = ids[static_cast<size_t>(y) * width + x];
    const float za = zbuf[static_cast<size_t>(y) * width + x];
    const int nx[4] = {x - 1, x + 1, x, x};
    const int ny[4] = {y, y, y - 1, y + 1};
    for (int k = 0; k < 4; ++k) {
      if (nx[k] < 0 || ny[k] < 0 || nx[k] >= width || ny[k] >= height) continue;
      const int b = ids[static_cast<size_t>(ny[k]) * width + nx[k]];
      if (a == b) continue;
      if ((a < 0) != (b < 0)) return true;
      // Different planes meeting here (not the continuation of one surface)?
      const ScreenTriangle& sb = screen[b];
      const double iz_b = sb.ip * x + sb.iq * y + sb.ir;
      if (std::abs(iz_b - za) > 0.005 * za) return true;
      const Triangle& ta = scene_.triangles[screen[a].triangle];
      const Triangle& tb = scene_.triangles[sb.triangle];
      const bool flat = scene_.surfaces[ta.surface].normal_mode == NormalMode::kFlat &&
                        scene_.surfaces[tb.surface].normal_mode == NormalMode::kFlat;
      if (flat && ta.normal.dot(tb.normal) < 0.98) return true;  // a crease (building corner)
    }
    return false;
  };
  ParallelTiles(num_tiles, num_threads_, [&](int tile) {
    const int row0 = tile * kTileRows, row1 = std::min(height, row0 + kTileRows);
    for (int y = row0; y < row1; ++y) {
      const int* idrow = &ids[static_cast<size_t>(y) * width];
      uint8_t* grey = out.grey.ptr<uint8_t>(y);
      float* depth = out.depth.ptr<float>(y);
      uint8_t* color = with_color ? out.color.ptr<uint8_t>(y) : nullptr;
      for (int x = 0; x < width; ++x) {
        double z = 0;
        Eigen::Vector3f radiance = shade(x, y, idrow[x], &z);
        depth[x] = static_cast<float>(z);
        if (edge_antialiasing_ && is_edge(x, y)) {
          // Candidate triangles: those visible in the 3x3 neighbourhood.
          int candidates[9], count = 0;
          bool sky_beside = false;
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const int xx = x + dx, yy = y + dy;
              if (xx < 0 || yy < 0 || xx >= width || yy >= height) continue;
              const int id = ids[static_cast<size_t>(yy) * width + xx];
              sky_beside |= id < 0;
              if (id >= 0 && std::find(candidates, candidates + count, id) == candidates + count) candidates[count++] = id;
            }
          static const double kOffsets[4][2] = {{-0.125, -0.375}, {0.375, -0.125}, {0.125, 0.375}, {-0.375, 0.125}};
          Eigen::Vector3f sum = radiance;
          int samples = 1;
          for (const auto& o : kOffsets) {
            const double sx = x + o[0], sy = y + o[1];
            int best = -1;
            double best_iz = min_inverse_depth;
            for (int c = 0; c < count; ++c) {
              const ScreenTriangle& st = screen[candidates[c]];
              bool inside = true;
              for (int e = 0; e < 3 && inside; ++e) inside = st.ea[e] * sx + st.eb[e] * sy + st.ec[e] >= 0;
              const double iz = st.ip * sx + st.iq * sy + st.ir;
              if (inside && iz > best_iz) {
                best_iz = iz;
                best = candidates[c];
              }
            }
            // No candidate covers the sample: a surface seen at no pixel centre around it (a ground strip
            // thinner than a pixel beyond ~45 m, a kerb face). Sky there would be a bright fringe below the
            // horizon that the other camera sees elsewhere; it is sky only where sky is seen beside it.
            if (best < 0 && !sky_beside && !uncovered_subsamples_see_sky_) continue;
            double unused = 0;
            sum += shade(sx, sy, best, &unused);
            ++samples;
          }
          radiance = sum / static_cast<float>(samples);  // centre + up to 4 sub-samples
        }
        // Camera: exposure gain/bias, vignetting, noise, 8-bit quantisation.
        const float vignette = static_cast<float>(lens.At(radial_position.Sq(x, y)));
        const float k = scale * vignette;
        const float bias = static_cast<float>(photometric.bias);
        const float lum = Luma(radiance.x(), radiance.y(), radiance.z());
        const uint64_t pixel_key = photometric.noise_seed ^ (static_cast<uint64_t>(y) << 32 | static_cast<uint32_t>(x));
        float noise = 0.f;
        if (photometric.noise_sigma > 0)
          noise = static_cast<float>(photometric.noise_sigma) * GaussFromBits(Mix(pixel_key));
        grey[x] = Quantise(k * lum + bias + noise);
        if (color) {
          for (int ch = 0; ch < 3; ++ch) {
            float cn = 0.f;
            if (photometric.noise_sigma > 0)
              cn = static_cast<float>(photometric.noise_sigma) * GaussFromBits(Mix(pixel_key + 0x1234567ull * (ch + 1)));
            color[3 * x + (2 - ch)] = Quantise(k * radiance[ch] + bias + cn);  // BGR
          }
        }
      }
    }
  });
  return out;
}

}  // namespace dvso::sim
