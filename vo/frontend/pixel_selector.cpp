#include "vo/frontend/pixel_selector.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace dvso::vo {

void PixelSelectorOptions::Check() const {
  Require(desired_points >= 1, "selector desired_points must be >= 1");
  Require(region_size >= 4, "selector region_size must be >= 4");
  Require(min_grad_hist_cut > 0 && min_grad_hist_cut < 1, "selector min_grad_hist_cut must be in (0, 1)");
  Require(min_grad_hist_add >= 0, "selector min_grad_hist_add must be >= 0");
  Require(grad_downweight_per_level > 0 && grad_downweight_per_level <= 1,
          "selector grad_downweight_per_level must be in (0, 1]");
  Require(border >= 3, "selector border must be >= 3 (pattern radius 2 + interpolation)");
  Require(max_adapt_iterations >= 1, "selector max_adapt_iterations must be >= 1");
}

std::vector<float> RegionThresholdsSq(const PyramidLevel& level, const PixelSelectorOptions& options, int* regions_x,
                                      int* regions_y) {
  const int rs = options.region_size;
  const int nx = (level.width + rs - 1) / rs;
  const int ny = (level.height + rs - 1) / rs;
  std::vector<float> thr(static_cast<size_t>(nx) * ny);
  constexpr int kBins = 50;
  std::vector<int> hist(kBins);
  for (int ry = 0; ry < ny; ++ry) {
    for (int rx = 0; rx < nx; ++rx) {
      std::fill(hist.begin(), hist.end(), 0);
      int total = 0;
      for (int y = ry * rs; y < std::min(level.height, (ry + 1) * rs); ++y) {
        for (int x = rx * rs; x < std::min(level.width, (rx + 1) * rs); ++x) {
          const int g = std::min(kBins - 1, static_cast<int>(std::sqrt(level.GradSq(x, y))));
          ++hist[g];
          ++total;
        }
      }
      const int target = static_cast<int>(options.min_grad_hist_cut * total + 0.5);
      int acc = 0;
      int bin = kBins - 1;
      for (int b = 0; b < kBins; ++b) {
        acc += hist[b];
        if (acc > target) {
          bin = b;
          break;
        }
      }
      thr[static_cast<size_t>(ry) * nx + rx] = static_cast<float>(bin + options.min_grad_hist_add);
    }
  }
  // 3x3 smoothing over regions, then square (the selector compares squared gradients).
  std::vector<float> smoothed(thr.size());
  for (int ry = 0; ry < ny; ++ry) {
    for (int rx = 0; rx < nx; ++rx) {
      float sum = 0;
      int n = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = rx + dx, y = ry + dy;
          if (x < 0 || y < 0 || x >= nx || y >= ny) continue;
          sum += thr[static_cast<size_t>(y) * nx + x];
          ++n;
        }
      }
      const float m = sum / n;
      smoothed[static_cast<size_t>(ry) * nx + rx] = m * m;
    }
  }
  *regions_x = nx;
  *regions_y = ny;
  return smoothed;
}

namespace {

struct Candidate {
  int x = -1, y = -1;
  float score = 0;
  bool valid() const { return x >= 0; }
  void Offer(int px, int py, float s) {
    if (s > score) {
      x = px;
      y = py;
      score = s;
    }
  }
};

std::vector<SelectedPixel> SelectWithBlockSize(const ImagePyramid& pyramid, const PixelSelectorOptions& options,
                                               const std::vector<float>& thr_sq, int nx, int pot) {
  const PyramidLevel& l0 = pyramid.level(0);
  const PyramidLevel* l1 = pyramid.num_levels() > 1 ? &pyramid.level(1) : nullptr;
  const PyramidLevel* l2 = pyramid.num_levels() > 2 ? &pyramid.level(2) : nullptr;
  const float dw1 = static_cast<float>(options.grad_downweight_per_level);
  const float dw2 = dw1 * dw1;
  const int rs = options.region_size;
  const int b = options.border;
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<float> angle(0.f, 6.2831853f);
  std::vector<SelectedPixel> out;
  const int p4 = 4 * pot, p2 = 2 * pot;
  for (int y4 = 0; y4 < l0.height; y4 += p4) {
    for (int x4 = 0; x4 < l0.width; x4 += p4) {
      const float ang = angle(rng);
      const float dirx = std::cos(ang), diry = std::sin(ang);
      Candidate best2;
      bool any4 = false;
      for (int y2 = y4; y2 < std::min(y4 + p4, l0.height); y2 += p2) {
        for (int x2 = x4; x2 < std::min(x4 + p4, l0.width); x2 += p2) {
          Candidate best1;
          bool any2 = false;
          for (int y1 = y2; y1 < std::min(y2 + p2, l0.height); y1 += pot) {
            for (int x1 = x2; x1 < std::min(x2 + p2, l0.width); x1 += pot) {
              Candidate best0;
              for (int y = std::max(y1, b); y < std::min(y1 + pot, l0.height - b); ++y) {
                for (int x = std::max(x1, b); x < std::min(x1 + pot, l0.width - b); ++x) {
                  const float th0 = thr_sq[static_cast<size_t>(y / rs) * nx + x / rs];
                  const Eigen::Vector3f& d0 = l0.At(x, y);
                  if (l0.GradSq(x, y) > th0) best0.Offer(x, y, std::fabs(d0[1] * dirx + d0[2] * diry) + 1e-6f);
                  if (l1 != nullptr && (x >> 1) < l1->width && (y >> 1) < l1->height) {
                    const Eigen::Vector3f& d1 = l1->At(x >> 1, y >> 1);
                    if (l1->GradSq(x >> 1, y >> 1) > th0 * dw1)
                      best1.Offer(x, y, std::fabs(d1[1] * dirx + d1[2] * diry) + 1e-6f);
                  }
                  if (l2 != nullptr && (x >> 2) < l2->width && (y >> 2) < l2->height) {
                    const Eigen::Vector3f& d2 = l2->At(x >> 2, y >> 2);
                    if (l2->GradSq(x >> 2, y >> 2) > th0 * dw2)
                      best2.Offer(x, y, std::fabs(d2[1] * dirx + d2[2] * diry) + 1e-6f);
                  }
                }
              }
              if (best0.valid()) {
                out.push_back({best0.x, best0.y, 0});
                any2 = true;
              }
            }
          }
          if (!any2 && best1.valid()) {
            out.push_back({best1.x, best1.y, 1});
            any2 = true;
          }
          any4 = any4 || any2;
        }
      }
      if (!any4 && best2.valid()) out.push_back({best2.x, best2.y, 2});
    }
  }
  return out;
}

}  // namespace

std::vector<SelectedPixel> SelectPixels(const ImagePyramid& pyramid, const PixelSelectorOptions& options,
                                        double* block_size_hint) {
  options.Check();
  const PyramidLevel& l0 = pyramid.level(0);
  int nx = 0, ny = 0;
  const std::vector<float> thr_sq = RegionThresholdsSq(l0, options, &nx, &ny);
  const double area = static_cast<double>(l0.width) * l0.height;
  double pot = std::max(1.0, std::sqrt(area / options.desired_points) * 0.6);
  if (block_size_hint != nullptr && *block_size_hint >= 1.0) pot = *block_size_hint;
  std::vector<SelectedPixel> best;
  double best_pot = pot;
  for (int it = 0; it < options.max_adapt_iterations; ++it) {
    const int ipot = std::max(1, static_cast<int>(std::lround(pot)));
    std::vector<SelectedPixel> sel = SelectWithBlockSize(pyramid, options, thr_sq, nx, ipot);
    const double ratio = static_cast<double>(sel.size()) / options.desired_points;
    const bool closer = best.empty() || std::fabs(std::log(std::max<double>(sel.size(), 1) / options.desired_points)) <
                                            std::fabs(std::log(std::max<double>(best.size(), 1) / options.desired_points));
    if (closer) {
      best = std::move(sel);
      best_pot = pot;
    }
    if (ratio > 0.8 && ratio < 1.25) break;
    // Count scales roughly with 1 / pot^2 (DSO makeMaps: sparsity * sqrt(quotient)).
    const double next = pot * std::sqrt(std::max(ratio, 0.05));
    if (ipot == 1 && next < 1) break;
    pot = std::max(1.0, next);
  }
  if (block_size_hint != nullptr) *block_size_hint = best_pot;
  if (best.size() > static_cast<size_t>(options.desired_points) * 5 / 4) {
    // Too many (pot cannot shrink further / grow finely enough): deterministic random subsample.
    std::mt19937 rng(options.seed + 1);
    std::shuffle(best.begin(), best.end(), rng);
    best.resize(options.desired_points);
    std::sort(best.begin(), best.end(),
              [](const SelectedPixel& a, const SelectedPixel& b) { return a.y != b.y ? a.y < b.y : a.x < b.x; });
  }
  return best;
}

}  // namespace dvso::vo
