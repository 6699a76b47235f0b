#include "core/simulator_textures.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <functional>
#include <random>

#include "core/error.h"

namespace dvso::sim {
namespace {

// ---------------------------------------------------------------- noise ----
uint32_t Hash3(uint32_t x, uint32_t y, uint32_t z) {
  uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u ^ z * 0xcb1ab31fu;
  h ^= h >> 16;
  h *= 0x7feb352du;
  h ^= h >> 15;
  h *= 0x846ca68bu;
  h ^= h >> 16;
  return h;
}
float HashUnit(int x, int y, uint32_t salt) {
  return (Hash3(static_cast<uint32_t>(x), static_cast<uint32_t>(y), salt) >> 8) * (1.0f / 16777216.0f);
}
float Smooth(float t) { return t * t * t * (t * (t * 6 - 15) + 10); }
int Wrap(int i, int period) { return ((i % period) + period) % period; }

// Tileable value noise in [0, 1): (x, y) in [0, 1) texture units, `period`
// lattice cells across the tile.
float ValueNoise(float x, float y, int period, uint32_t salt) {
  const float fx = x * period, fy = y * period;
  const int ix = static_cast<int>(std::floor(fx)), iy = static_cast<int>(std::floor(fy));
  const float tx = Smooth(fx - ix), ty = Smooth(fy - iy);
  const int x0 = Wrap(ix, period), x1 = Wrap(ix + 1, period);
  const int y0 = Wrap(iy, period), y1 = Wrap(iy + 1, period);
  const float a = HashUnit(x0, y0, salt), b = HashUnit(x1, y0, salt);
  const float c = HashUnit(x0, y1, salt), d = HashUnit(x1, y1, salt);
  return (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
}
// Fractal sum of `octaves` value-noise layers, centred on 0, roughly in [-0.5, 0.5].
float Fbm(float x, float y, int period, int octaves, float gain, uint32_t salt) {
  float sum = 0, amp = 1, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * (ValueNoise(x, y, period << o, salt + 977u * o) - 0.5f);
    norm += amp;
    amp *= gain;
  }
  return sum / norm;
}

using Image = std::vector<float>;

struct Canvas {
  int n;
  Image px;
  explicit Canvas(int size, float value = 0.f) : n(size), px(size * size, value) {}
  float& at(int x, int y) { return px[Wrap(y, n) * n + Wrap(x, n)]; }
  template <typename F>
  void ForEach(F f) {  // f(x01, y01, value&)
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) f((x + 0.5f) / n, (y + 0.5f) / n, px[y * n + x]);
  }
  // Soft disc (radius in texels) blended towards `value` with opacity alpha.
  void Disc(float cx, float cy, float rx, float ry, float value, float alpha) {
    const int x0 = static_cast<int>(std::floor(cx - rx - 1)), x1 = static_cast<int>(std::ceil(cx + rx + 1));
    const int y0 = static_cast<int>(std::floor(cy - ry - 1)), y1 = static_cast<int>(std::ceil(cy + ry + 1));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const float dx = (x + 0.5f - cx) / rx, dy = (y + 0.5f - cy) / ry;
        const float r = std::sqrt(dx * dx + dy * dy);
        const float cover = std::clamp((1.f - r) * std::min(rx, ry) + 0.5f, 0.f, 1.f) * alpha;
        float& p = at(x, y);
        p += (value - p) * cover;
      }
  }
  // Axis-aligned rectangle [x0, x1) x [y0, y1) (texels, wraps) set to value * (1 + noise).
  void Rect(float x0, float y0, float x1, float y1, float value, float alpha = 1.f) {
    for (int y = static_cast<int>(std::floor(y0)); y < static_cast<int>(std::ceil(y1)); ++y)
      for (int x = static_cast<int>(std::floor(x0)); x < static_cast<int>(std::ceil(x1)); ++x) {
        // Partial coverage of border texels keeps the edges anti-aliased.
        const float cx = std::clamp(std::min(x + 1.f, x1) - std::max(static_cast<float>(x), x0), 0.f, 1.f);
        const float cy = std::clamp(std::min(y + 1.f, y1) - std::max(static_cast<float>(y), y0), 0.f, 1.f);
        float& p = at(x, y);
        p += (value - p) * cx * cy * alpha;
      }
  }
  void Blur3() {  // 1-2-1 separable blur, keeps tileability
    Image tmp(px.size());
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) tmp[y * n + x] = 0.25f * at(x - 1, y) + 0.5f * at(x, y) + 0.25f * at(x + 1, y);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x)
        px[y * n + x] = 0.25f * tmp[Wrap(y - 1, n) * n + x] + 0.5f * tmp[y * n + x] + 0.25f * tmp[Wrap(y + 1, n) * n + x];
  }
  Image Done() {
    for (float& p : px) p = std::clamp(p, 0.02f, 1.f);
    return std::move(px);
  }
};

// ------------------------------------------------------------- materials ---
Image Asphalt(int n, std::mt19937_64& rng, uint32_t s) {
  Canvas c(n);
  c.ForEach([&](float x, float y, float& p) {
    // Patches of ~0.3-1 m (visible from afar) over fine grain.
    p = 0.36f + 0.18f * Fbm(x, y, 4, 6, 0.7f, s) + 0.30f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
  });
  c.Blur3();  // grain of ~2 texels (1 cm): pebbles, not per-texel static
  c.ForEach([&](float x, float y, float& p) { p += 0.14f * (HashUnit(int(x * n), int(y * n), s + 2) - 0.5f); });
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < n * n / 400; ++i)  // light and dark pebbles
    c.Disc(u(rng) * n, u(rng) * n, 1.0f + 1.5f * u(rng), 1.0f + 1.5f * u(rng), u(rng) < 0.5f ? 0.62f : 0.18f, 0.8f);
  for (int k = 0; k < 1; ++k) {  // a crack: dark random walk
    float x = u(rng) * n, y = u(rng) * n, a = u(rng) * 6.283f;
    for (int step = 0; step < n; ++step) {
      a += (u(rng) - 0.5f) * 0.6f;
      x += std::cos(a);
      y += std::sin(a);
      c.Disc(x, y, 1.0f, 1.0f, 0.2f, 0.35f);
    }
  }
  return c.Done();
}

Image Paving(int n, std::mt19937_64& rng, uint32_t s) {
  Canvas c(n);
  const int stones = 8;  // 8 x 8 stones per tile, running bond
  const float w = static_cast<float>(n) / stones;
  c.ForEach([&](float x, float y, float& p) {
    const int row = static_cast<int>(y * stones);
    const float sx = x * stones + (row % 2) * 0.5f;
    const int col = static_cast<int>(std::floor(sx));
    const float fx = sx - col, fy = y * stones - row;
    const float edge = std::min(std::min(fx, 1 - fx), std::min(fy, 1 - fy)) * w;  // texels to the joint
    const float stone = 0.50f + 0.16f * (HashUnit(Wrap(col, stones), row, s) - 0.5f) + 0.08f * Fbm(x, y, 16, 3, 0.5f, s + 3);
    const float bevel = std::clamp(edge / 2.5f, 0.f, 1.f);
    p = 0.22f + (stone - 0.22f) * bevel + 0.07f * (HashUnit(int(x * n), int(y * n), s + 4) - 0.5f);
  });
  c.Blur3();
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 60; ++i) c.Disc(u(rng) * n, u(rng) * n, 3 + 8 * u(rng), 3 + 8 * u(rng), 0.3f, 0.35f);  // stains
  return c.Done();
}

Image Speckled(int n, uint32_t s, float base, float speckle, float fbm_amp, int period) {
  Canvas c(n);
  c.ForEach([&](float x, float y, float& p) {
    p = base + fbm_amp * Fbm(x, y, period, 5, 0.55f, s) + speckle * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
  });
  c.Blur3();
  return c.Done();
}

Image Curb(int n, uint32_t s) {
  Canvas c(n);
  c.ForEach([&](float x, float y, float& p) {
    p = 0.62f + 0.06f * Fbm(x, y, 8, 4, 0.5f, s) + 0.16f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
    const float joint = std::min(x, 1 - x) * n;  // one joint per tile (1 m blocks)
    if (joint < 2.f) p *= 0.55f + 0.2f * joint;
  });
  c.Blur3();
  return c.Done();
}

Image Grass(int n, std::mt19937_64& rng, uint32_t s) {
  Canvas c(n);
  c.ForEach([&](float x, float y, float& p) {
    p = 0.30f + 0.14f * Fbm(x, y, 4, 6, 0.65f, s) + 0.10f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
  });
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < n * n / 40; ++i) {  // blades: short bright/dark streaks
    const float x = u(rng) * n, y = u(rng) * n, a = u(rng) * 3.1416f, len = 2 + 4 * u(rng);
    const float v = u(rng) < 0.6f ? 0.48f : 0.14f;
    for (float t = 0; t < len; t += 0.7f) c.Disc(x + t * std::cos(a), y + t * std::sin(a), 0.7f, 0.7f, v, 0.4f);
  }
  return c.Done();
}

// Facade tile: 2 bays x 2 storeys (the tile is 6.4 m square, 1.25 cm per texel
// at 512). `style`: 0 plaster, 1 brick, 2 concrete panels, 3 stone blocks.
Image Facade(int n, int style, std::mt19937_64& rng, uint32_t s) {
  Canvas c(n);
  const float m = n / 6.4f;  // texels per metre
  c.ForEach([&](float x, float y, float& p) {
    const float noise = 0.07f * Fbm(x, y, 8, 5, 0.55f, s) + 0.06f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
    switch (style) {
      case 0:
        p = 0.68f + noise;
        break;
      case 1: {  // bricks 24 x 7.5 cm with mortar
        const float by = y * 6.4f / 0.08f;
        const int row = static_cast<int>(by);
        const float bx = x * 6.4f / 0.2f + (row % 2) * 0.5f;
        const int col = static_cast<int>(bx);
        const float fx = bx - col, fy = by - row;
        const bool mortar = fx < 0.06f || fy < 0.14f;
        p = mortar ? 0.70f + noise * 0.5f
                   : 0.42f + 0.14f * (HashUnit(Wrap(col, 32), Wrap(row, 80), s + 5) - 0.5f) + noise;
        break;
      }
      case 2: {  // concrete panels 1.6 x 1.6 m
        const float fx = std::fmod(x * 6.4f, 1.6f), fy = std::fmod(y * 6.4f, 1.6f);
        const bool joint = fx < 0.025f || fy < 0.025f;
        p = joint ? 0.35f : 0.58f + 0.08f * (HashUnit(int(x * 4), int(y * 4), s + 6) - 0.5f) + 1.3f * noise;
        break;
      }
      case 4: {  // horizontal boards 16 cm high (siding), a shadow line under each
        const float fy = std::fmod(y * 6.4f, 0.16f) / 0.16f;
        const int board = static_cast<int>(y * 6.4f / 0.16f);
        p = 0.60f + 0.10f * (HashUnit(board, 0, s + 8) - 0.5f) + 0.8f * noise - (fy < 0.12f ? 0.18f : 0.f);
        break;
      }
      case 5: {  // glass curtain wall: dark panes 1.6 x 1.6 m between bright mullions
        const float fx = std::fmod(x * 6.4f, 1.6f), fy = std::fmod(y * 6.4f, 1.6f);
        const bool mullion = fx < 0.08f || fy < 0.08f;
        p = mullion ? 0.72f + noise * 0.5f
                    : 0.16f + 0.12f * fy + 0.10f * (HashUnit(int(x * 4), int(y * 4), s + 9) - 0.5f) + 0.5f * noise;
        break;
      }
      default: {  // stone blocks 0.8 x 0.4 m
        const int row = static_cast<int>(y * 16);
        const float bx = x * 8 + (row % 2) * 0.5f;
        const int col = static_cast<int>(bx);
        const bool joint = (bx - col) < 0.02f || (y * 16 - row) < 0.04f;
        p = joint ? 0.38f : 0.60f + 0.12f * (HashUnit(Wrap(col, 8), row, s + 7) - 0.5f) + 1.2f * noise;
      }
    }
  });
  std::uniform_real_distribution<float> u(0.f, 1.f);
  if (style == 5) return c.Done();  // the curtain wall is all window
  const float win_w = (1.0f + 0.5f * u(rng)) * m, win_h = (1.3f + 0.5f * u(rng)) * m;
  const float sill = 0.9f * m, frame = 0.07f * m;
  const bool mullion = u(rng) < 0.6f;
  for (int by = 0; by < 2; ++by)
    for (int bx = 0; bx < 2; ++bx) {
      // v (rows) grows upwards on facades: sill 0.9 m above each storey's floor.
      const float x0 = (bx * 3.2f * m) + (3.2f * m - win_w) / 2, y0 = by * 3.2f * m + sill;
      const float y1 = y0 + win_h;
      c.Rect(x0 - frame * 1.5f, y0 - 0.08f * m, x0 + win_w + frame * 1.5f, y0, 0.85f);  // sill
      c.Rect(x0, y0, x0 + win_w, y1, 0.88f);                                             // frame
      const float glass = 0.10f + 0.25f * u(rng);
      c.Rect(x0 + frame, y0 + frame, x0 + win_w - frame, y1 - frame, glass);
      if (u(rng) < 0.4f)  // curtain
        c.Rect(x0 + frame, y0 + frame, x0 + frame + (win_w - 2 * frame) * (0.3f + 0.5f * u(rng)), y1 - frame,
               0.55f + 0.3f * u(rng), 0.9f);
      // Sky reflection: brighter towards the top of the pane.
      for (float yy = y0 + frame; yy < y1 - frame; yy += 1.f)
        c.Rect(x0 + frame, yy, x0 + win_w - frame, yy + 1.f, glass + 0.12f * (yy - y0) / win_h, 1.f);
      if (mullion) {
        c.Rect(x0 + win_w / 2 - frame / 2, y0, x0 + win_w / 2 + frame / 2, y1, 0.85f);
        c.Rect(x0, y0 + win_h * 0.35f, x0 + win_w, y0 + win_h * 0.35f + frame, 0.85f);
      }
    }
  c.Blur3();
  return c.Done();
}

// True within 1.5 texels of a vertical panel seam of the car paints (tile 2 m, a seam every metre).
bool OnCarPanelSeam(float x, int n) {
  return std::min(std::fmod(x * 2.f, 1.f), 1 - std::fmod(x * 2.f, 1.f)) * n / 2 < 1.5f;
}

Image CarPaint(int n, uint32_t s) {
  Canvas c(n);  // tile 2 m; panel lines every metre, mild dirt towards the bottom
  c.ForEach([&](float x, float y, float& p) {
    p = 0.80f + 0.05f * Fbm(x, y, 8, 4, 0.5f, s) + 0.03f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
    if (OnCarPanelSeam(x, n)) p *= 0.5f;
    if (std::fabs(y - 0.5f) * n < 1.2f) p *= 0.7f;
  });
  return c.Done();
}

// Car paint as bodies look from a few metres (Appearance::car_detail): the surroundings' reflections as
// sharp-edged dark patches (trees, buildings) over soft blotches from ~30 cm down to ~2 cm, grain, road dirt spots
// and door handles, with the plain paint's vertical panel seams every metre. With only the plain paint a van's side
// is nearly uniform, so within 5 m neither the Stereo DSO labels nor the photometric loss had anything to match on
// (docs/stacknet.md, sessions 9 and 36).
constexpr float kCarReflectionContrast = 0.3f;  // albedo; the plain paint varies by ~0.05
constexpr float kCarReflectionCover = 0.06f;    // fBm level above which a reflected dark object starts (~35 % of the body)
constexpr float kCarReflectionEdge = 20.f;      // ramp steepness: edges ~1/20 of the fBm range wide, i.e. sharp
Image CarPaintDetailed(int n, uint32_t s) {
  Canvas c(n);  // tile 2 m, as CarPaint
  c.ForEach([&](float x, float y, float& p) {
    const float sharp =
        std::clamp((Fbm(x, y, 4, 6, 0.65f, s + 3) - kCarReflectionCover) * kCarReflectionEdge, 0.f, 1.f);
    p = 0.80f + 0.5f * kCarReflectionContrast * Fbm(x, y, 6, 5, 0.6f, s) - kCarReflectionContrast * sharp +
        0.06f * (HashUnit(int(x * n / 2), int(y * n / 2), s + 1) - 0.5f);
    if (OnCarPanelSeam(x, n)) p *= 0.5f;
  });
  std::mt19937_64 rng(s + 2);  // own generator: the bank's other textures stay as they were
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < n * n / 800; ++i) {  // dirt and chips: dark and light spots of 1-4 texels
    const float r = 1.f + 3.f * u(rng);
    c.Disc(u(rng) * n, u(rng) * n, r, r * (0.5f + 0.5f * u(rng)), u(rng) < 0.7f ? 0.3f : 0.95f, 0.6f);
  }
  for (int door = 0; door < 2; ++door)  // a handle behind each seam (seams every metre)
    c.Disc((door * 0.5f + 0.06f) * n, 0.3f * n, 0.03f * n, 0.008f * n, 0.25f, 0.9f);
  c.Blur3();
  return c.Done();
}

Image Leaves(int n, std::mt19937_64& rng) {
  Canvas c(n, 0.22f);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < n * n / 30; ++i) {
    const float r = 2.f + 4.f * u(rng);
    c.Disc(u(rng) * n, u(rng) * n, r, r * (0.5f + 0.5f * u(rng)), 0.25f + 0.6f * u(rng), 0.85f);
  }
  return c.Done();
}

Image Sign(int n) {
  Canvas c(n, 0.9f);  // one tile = the whole plate: ring, bar and a border
  c.ForEach([&](float x, float y, float& p) {
    const float r = std::hypot(x - 0.5f, y - 0.5f);
    if (r > 0.30f && r < 0.44f) p = 0.25f;
    if (std::fabs(y - 0.5f) < 0.06f && r < 0.3f) p = 0.1f;
    if (std::min(std::min(x, 1 - x), std::min(y, 1 - y)) < 0.03f) p = 0.3f;
  });
  c.Blur3();
  return c.Done();
}

// Concrete road (tile 2.5 m): slabs 2.5 m long with a dark joint across, fine
// grain, a few patches.
Image RoadConcrete(int n, std::mt19937_64& rng, uint32_t s) {
  Canvas c(n);
  c.ForEach([&](float x, float y, float& p) {
    p = 0.52f + 0.10f * Fbm(x, y, 4, 5, 0.6f, s) + 0.16f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
    if (std::min(y, 1 - y) * n < 1.5f) p *= 0.5f;
  });
  c.Blur3();
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < 40; ++i) c.Disc(u(rng) * n, u(rng) * n, 4 + 14 * u(rng), 4 + 14 * u(rng), 0.35f, 0.3f);
  return c.Done();
}

// Dry grass: bright patchy base with bare spots.
Image GrassDry(int n, std::mt19937_64& rng, uint32_t s) {
  Canvas c(n);
  c.ForEach([&](float x, float y, float& p) {
    const float patch = Fbm(x, y, 4, 5, 0.6f, s);
    p = 0.45f + 0.25f * patch + 0.14f * (HashUnit(int(x * n), int(y * n), s + 1) - 0.5f);
  });
  std::uniform_real_distribution<float> u(0.f, 1.f);
  for (int i = 0; i < n * n / 80; ++i) {
    const float x = u(rng) * n, y = u(rng) * n, a = u(rng) * 3.1416f, len = 2 + 3 * u(rng);
    for (float t = 0; t < len; t += 0.7f) c.Disc(x + t * std::cos(a), y + t * std::sin(a), 0.7f, 0.7f, 0.2f, 0.4f);
  }
  return c.Done();
}

// Mip level: 2x2 box filter (sizes are powers of two).
std::vector<float> Downsample(const std::vector<float>& src, int size) {
  const int h = size / 2;
  std::vector<float> dst(h * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < h; ++x)
      dst[y * h + x] = 0.25f * (src[2 * y * size + 2 * x] + src[2 * y * size + 2 * x + 1] +
                                src[(2 * y + 1) * size + 2 * x] + src[(2 * y + 1) * size + 2 * x + 1]);
  return dst;
}

}  // namespace

MipTexture::MipTexture(std::vector<float> level0, int size) {
  Require(size > 0 && (size & (size - 1)) == 0 && level0.size() == static_cast<size_t>(size) * size,
          "texture size must be a power of two");
  levels_.push_back(std::move(level0));
  sizes_.push_back(size);
  while (sizes_.back() > 1) {
    levels_.push_back(Downsample(levels_.back(), sizes_.back()));
    sizes_.push_back(sizes_.back() / 2);
  }
}

float MipTexture::Sample(double u, double v, float footprint) const {
  const float fu = static_cast<float>(u - std::floor(u)), fv = static_cast<float>(v - std::floor(v));
  return Trilinear(fu, fv, footprint > 1.f ? std::log2(footprint) : 0.f);
}

float MipTexture::SampleAniso(double u, double v, float dudx, float dvdx, float dudy, float dvdy,
                              int max_taps) const {
  const float n = static_cast<float>(sizes_[0]);
  const float lx = std::sqrt(dudx * dudx + dvdx * dvdx) * n, ly = std::sqrt(dudy * dudy + dvdy * dvdy) * n;
  const float major = std::max(lx, ly), minor = std::min(lx, ly);
  const float fu = static_cast<float>(u - std::floor(u)), fv = static_cast<float>(v - std::floor(v));
  if (major <= 1.f) return Bilinear(0, fu * n, fv * n);
  const int taps = std::clamp(static_cast<int>(std::ceil(major / std::max(minor, 1e-3f))), 1, max_taps);
  const float lod = std::log2(std::max(std::max(major / taps, minor), 1.f));
  if (taps == 1) return Trilinear(fu, fv, lod);
  const float au = lx >= ly ? dudx : dudy, av = lx >= ly ? dvdx : dvdy;
  float sum = 0.f;
  for (int k = 0; k < taps; ++k) {
    const float t = (k + 0.5f) / taps - 0.5f;
    float su = fu + t * au, sv = fv + t * av;
    su -= std::floor(su);
    sv -= std::floor(sv);
    sum += Trilinear(su, sv, lod);
  }
  return sum / taps;
}

TextureBank::TextureBank(uint64_t seed, int size) {
  Require(size >= 64 && (size & (size - 1)) == 0, "texture size must be a power of two >= 64");
  textures_.resize(kNumTextures);
  const uint32_t s = static_cast<uint32_t>(seed * 2654435761u + 12345u);
  std::mt19937_64 rng(seed ^ 0x5eed7e57u);
  auto set = [&](int id, Image img) { textures_[id] = MipTexture(std::move(img), size); };
  set(kTexAsphalt, Asphalt(size, rng, s + 100));
  set(kTexPaving, Paving(size, rng, s + 200));
  set(kTexCurb, Curb(size, s + 300));
  set(kTexGrass, Grass(size, rng, s + 400));
  set(kTexDirt, Speckled(size, s + 500, 0.38f, 0.14f, 0.22f, 4));
  for (int style = 0; style < kNumFacadeStyles; ++style)
    set(kTexFacadePlaster + style, Facade(size, style, rng, s + 600 + 50 * style));
  set(kTexCarPaint, CarPaint(size, s + 900));
  set(kTexCarGlass, Speckled(size, s + 1000, 0.16f, 0.02f, 0.20f, 2));
  set(kTexRubber, Speckled(size, s + 1100, 0.12f, 0.06f, 0.06f, 8));
  set(kTexMetal, Speckled(size, s + 1200, 0.55f, 0.10f, 0.15f, 4));
  set(kTexBark, Speckled(size, s + 1300, 0.30f, 0.20f, 0.30f, 8));
  set(kTexLeaves, Leaves(size, rng));
  set(kTexSign, Sign(size));
  Canvas macro(size);
  macro.ForEach([&](float x, float y, float& p) { p = 0.5f + 0.9f * Fbm(x, y, 4, 5, 0.55f, s + 1400); });
  set(kTexMacro, macro.Done());
  Canvas clouds(size);
  clouds.ForEach([&](float x, float y, float& p) {
    p = std::clamp(1.8f * (Fbm(x, y, 3, 6, 0.55f, s + 1500) + 0.05f), 0.f, 1.f) * 0.9f + 0.05f;
  });
  set(kTexClouds, clouds.Done());
  for (int style = kNumFacadeStyles; style < kNumFacadeStyles + kNumExtraFacadeStyles; ++style)
    set(FacadeTexture(style), Facade(size, style, rng, s + 600 + 50 * style));
  set(kTexRoadConcrete, RoadConcrete(size, rng, s + 1600));
  set(kTexGrassDry, GrassDry(size, rng, s + 1700));
  set(kTexCarPaintDetailed, CarPaintDetailed(size, s + 1800));
}

}  // namespace dvso::sim
