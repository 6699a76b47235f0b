// Procedural, tileable, mip-mapped textures of the synthetic street world
// (asphalt, paving, facades, leaves, ...). They are generated once per seed
// and then only looked up: evaluating noise per pixel would be far too slow
// for the 5 frames/s target, and the mip chain gives anti-aliased (filtered)
// lookups so that distant surfaces do not shimmer between views, which would
// break the photo-consistency that direct odometry (DSO) relies on.
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

namespace dvso::sim {

enum TextureId : int {
  kTexAsphalt = 0,
  kTexPaving,
  kTexCurb,
  kTexGrass,
  kTexDirt,
  kTexFacadePlaster,
  kTexFacadeBrick,
  kTexFacadePanels,
  kTexFacadeStone,
  kTexCarPaint,
  kTexCarGlass,
  kTexRubber,
  kTexMetal,
  kTexBark,
  kTexLeaves,
  kTexSign,
  kTexMacro,   // low-frequency stains, multiplied on top of detail textures
  kTexClouds,  // sky
  // Extra materials of the varied appearance (SceneOptions::appearance); generated
  // after the others, so the textures above do not change with them.
  kTexFacadeSiding,   // horizontal boards (cladding) with windows
  kTexFacadeGlass,    // glass curtain wall: large panes between mullions
  kTexRoadConcrete,   // concrete road slabs with joints
  kTexGrassDry,       // sparse, patchy grass
  kTexCarPaintDetailed,  // car paint with reflections, dirt and handles (Appearance::car_detail)
  kNumTextures
};
constexpr int kNumFacadeStyles = 4;  // kTexFacadePlaster .. kTexFacadeStone
constexpr int kNumExtraFacadeStyles = 2;  // kTexFacadeSiding, kTexFacadeGlass
// Texture of facade style i in [0, kNumFacadeStyles + kNumExtraFacadeStyles).
inline int FacadeTexture(int style) {
  return style < kNumFacadeStyles ? kTexFacadePlaster + style : kTexFacadeSiding + (style - kNumFacadeStyles);
}

// A square, power-of-two, tileable single-channel texture (albedo in [0, 1])
// with its full mip chain (2x2 box filter per level).
class MipTexture {
 public:
  MipTexture() = default;
  // level0 holds size*size values, row-major; size must be a power of two.
  MipTexture(std::vector<float> level0, int size);

  int size() const { return sizes_.empty() ? 0 : sizes_[0]; }
  int num_levels() const { return static_cast<int>(levels_.size()); }
  // Mean value of the texture (the 1x1 mip level).
  float mean() const { return levels_.back()[0]; }

  // Trilinear lookup at (u, v) in tiles (the texture repeats with period 1),
  // filtered over a footprint of `footprint` level-0 texels.
  float Sample(double u, double v, float footprint) const;
  // Anisotropic lookup: the pixel footprint is given by the derivatives of
  // (u, v) in tiles per pixel along image x and y; up to max_taps trilinear
  // taps along the major axis (needed for the road seen at grazing angles).
  float SampleAniso(double u, double v, float dudx, float dvdx, float dudy, float dvdy,
                    int max_taps) const;
  // Bilinear lookup in mip level `level` at texel coordinates of that level.
  inline float Bilinear(int level, float x, float y) const {
    const int n = sizes_[level], mask = n - 1;
    const float* p = levels_[level].data();
    x -= 0.5f;
    y -= 0.5f;
    const float flx = std::floor(x), fly = std::floor(y);
    const float tx = x - flx, ty = y - fly;
    const int x0 = static_cast<int>(flx) & mask, y0 = static_cast<int>(fly) & mask;
    const int x1 = (x0 + 1) & mask, y1 = (y0 + 1) & mask;
    const float a = p[y0 * n + x0], b = p[y0 * n + x1], c = p[y1 * n + x0], d = p[y1 * n + x1];
    const float top = a + (b - a) * tx, bottom = c + (d - c) * tx;
    return top + (bottom - top) * ty;
  }

 private:
  // Blend of the two mip levels around `lod` at (fu, fv) in [0, 1).
  inline float Trilinear(float fu, float fv, float lod) const {
    const int last = static_cast<int>(levels_.size()) - 1;
    if (lod <= 0.f) return Bilinear(0, fu * sizes_[0], fv * sizes_[0]);
    if (lod >= last) return levels_[last][0];
    const int l0 = static_cast<int>(lod);
    const float t = lod - l0;
    const float a = Bilinear(l0, fu * sizes_[l0], fv * sizes_[l0]);
    if (t < 0.02f) return a;
    const float b = Bilinear(l0 + 1, fu * sizes_[l0 + 1], fv * sizes_[l0 + 1]);
    return a + (b - a) * t;
  }
  std::vector<std::vector<float>> levels_;
  std::vector<int> sizes_;
};

// All textures of the world, generated deterministically from a seed.
class TextureBank {
 public:
  explicit TextureBank(uint64_t seed, int size = 512);
  const MipTexture& operator[](int id) const { return textures_[id]; }

 private:
  std::vector<MipTexture> textures_;
};

}  // namespace dvso::sim
