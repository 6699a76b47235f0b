#include "vo/frame/stereo_brightness.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "core/statistics.h"

namespace dvso::vo {

namespace {

// Every step-th intensity of `level` in columns [x_begin, x_end), sorted.
std::vector<float> SortedSamples(const PyramidLevel& level, int x_begin, int x_end, int step) {
  std::vector<float> samples;
  samples.reserve(static_cast<size_t>((x_end - x_begin) / step + 1) * (level.height / step + 1));
  for (int y = 0; y < level.height; y += step) {
    for (int x = x_begin; x < x_end; x += step) samples.push_back(level.Intensity(x, y));
  }
  std::sort(samples.begin(), samples.end());
  return samples;
}

// Value at quantile level q of sorted samples (linear between order statistics).
float Quantile(const std::vector<float>& sorted, double q) {
  const double position = q * static_cast<double>(sorted.size() - 1);
  const size_t i = static_cast<size_t>(position);
  if (i + 1 >= sorted.size()) return sorted.back();
  const double t = position - static_cast<double>(i);
  return static_cast<float>((1 - t) * sorted[i] + t * sorted[i + 1]);
}

}  // namespace

void StereoBrightnessOptions::Check() const {
  Require(sample_step >= 1, "stereo_brightness.sample_step must be >= 1");
  Require(border_fraction >= 0 && border_fraction < 0.5, "stereo_brightness.border_fraction must be in [0, 0.5)");
  Require(min_quantile >= 0 && min_quantile < max_quantile && max_quantile <= 1,
          "stereo_brightness quantiles must satisfy 0 <= min_quantile < max_quantile <= 1");
  Require(num_quantiles >= 3, "stereo_brightness.num_quantiles must be >= 3");
  Require(huber_threshold > 0, "stereo_brightness.huber_threshold must be > 0");
  Require(max_gain_ratio > 1, "stereo_brightness.max_gain_ratio must be > 1");
  Require(min_matched_points >= 3, "stereo_brightness.min_matched_points must be >= 3");
  Require(max_matching_passes >= 1, "stereo_brightness.max_matching_passes must be >= 1");
  Require(rematch_change > 0, "stereo_brightness.rematch_change must be > 0");
  Require(max_radial > 0 && max_radial < 1, "stereo_brightness.max_radial must be in (0, 1)");
  Require(radial_pool_keyframes >= 0, "stereo_brightness.radial_pool_keyframes must be >= 0");
}

std::optional<StereoBrightness> FitBrightnessTransfer(const std::vector<double>& x, const std::vector<double>& y,
                                                      double huber_threshold, double max_gain_ratio) {
  Require(x.size() == y.size(), "brightness fit: sample vectors differ in length");
  constexpr size_t kMinSamples = 3;
  if (x.size() < kMinSamples) return std::nullopt;
  constexpr int kReweightingIterations = 5;
  std::vector<double> w(x.size(), 1.0);
  StereoBrightness fit;
  for (int iteration = 0; iteration < kReweightingIterations; ++iteration) {
    // Weighted means, then the centred sums (numerically stable for intensities ~100).
    double sw = 0, mx = 0, my = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      sw += w[i];
      mx += w[i] * x[i];
      my += w[i] * y[i];
    }
    mx /= sw;
    my /= sw;
    double sxx = 0, syy = 0, sxy = 0;
    for (size_t i = 0; i < x.size(); ++i) {
      sxx += w[i] * (x[i] - mx) * (x[i] - mx);
      syy += w[i] * (y[i] - my) * (y[i] - my);
      sxy += w[i] * (x[i] - mx) * (y[i] - my);
    }
    constexpr double kMinSpread = 1e-6;  // weighted variance below this: no slope to fit
    if (!(sxx > kMinSpread * sw) || !(std::abs(sxy) > kMinSpread * sw)) return std::nullopt;
    // Orthogonal (total least squares) slope: both sides carry the same sensor noise, and the
    // ordinary slope sxy / sxx would shrink by var(noise) / var(x) (0.5 % on a simulated world).
    fit.gain = (syy - sxx + std::sqrt((syy - sxx) * (syy - sxx) + 4 * sxy * sxy)) / (2 * sxy);
    fit.bias = my - fit.gain * mx;
    for (size_t i = 0; i < x.size(); ++i) {
      const double residual = std::abs(y[i] - (fit.gain * x[i] + fit.bias));
      w[i] = residual <= huber_threshold ? 1.0 : huber_threshold / residual;
    }
  }
  if (!std::isfinite(fit.gain) || !std::isfinite(fit.bias) || fit.gain < 1.0 / max_gain_ratio ||
      fit.gain > max_gain_ratio) {
    return std::nullopt;
  }
  return fit;
}

std::optional<double> FitRadialTerm(const std::vector<double>& x, const std::vector<double>& y,
                                    const std::vector<double>& rho_sq, double huber_threshold, double max_radial) {
  Require(x.size() == y.size() && x.size() == rho_sq.size(), "brightness fit: sample vectors differ in length");
  constexpr size_t kMinSamples = 4;
  if (x.size() < kMinSamples) return std::nullopt;
  // The joint Huber-reweighted least squares y = g x + h rho^2 x + bias (linear in g, h = g * radial,
  // bias). Noise in x shrinks g and h nearly alike, so radial = h / g keeps almost none of that bias
  // (g itself would: that is why gain and bias come from the orthogonal fit, FitBrightnessTransferAtRadial).
  constexpr int kReweightingIterations = 5;
  std::vector<double> w(x.size(), 1.0);
  Eigen::Vector3d theta = Eigen::Vector3d::Zero();
  for (int iteration = 0; iteration < kReweightingIterations; ++iteration) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
    for (size_t i = 0; i < x.size(); ++i) {
      const Eigen::Vector3d a(x[i], rho_sq[i] * x[i], 1.0);
      A.noalias() += w[i] * a * a.transpose();
      rhs += w[i] * y[i] * a;
    }
    const Eigen::LDLT<Eigen::Matrix3d> ldlt(A);
    constexpr double kMinPivotRatio = 1e-12;  // no spread in rho^2 or x: nothing radial to fit
    const Eigen::Vector3d d = ldlt.vectorD().cwiseAbs();
    if (ldlt.info() != Eigen::Success || !(d.minCoeff() > kMinPivotRatio * d.maxCoeff())) return std::nullopt;
    theta = ldlt.solve(rhs);
    for (size_t i = 0; i < x.size(); ++i) {
      const double residual = std::abs(y[i] - (theta[0] + theta[1] * rho_sq[i]) * x[i] - theta[2]);
      w[i] = residual <= huber_threshold ? 1.0 : huber_threshold / residual;
    }
  }
  const double radial = theta[1] / theta[0];
  if (!std::isfinite(radial) || std::abs(radial) > max_radial) return std::nullopt;
  return radial;
}

std::optional<StereoBrightness> FitBrightnessTransferAtRadial(const std::vector<double>& x, const std::vector<double>& y,
                                                              const std::vector<double>& rho_sq, double radial,
                                                              double huber_threshold, double max_gain_ratio) {
  Require(x.size() == rho_sq.size(), "brightness fit: sample vectors differ in length");
  std::vector<double> scaled(x.size());
  for (size_t i = 0; i < x.size(); ++i) scaled[i] = x[i] * (1.0 + radial * rho_sq[i]);
  std::optional<StereoBrightness> fit = FitBrightnessTransfer(scaled, y, huber_threshold, max_gain_ratio);
  if (fit) fit->radial = radial;
  return fit;
}

std::optional<StereoBrightness> FitRadialBrightnessTransfer(const std::vector<double>& x, const std::vector<double>& y,
                                                            const std::vector<double>& rho_sq, double huber_threshold,
                                                            double max_gain_ratio, double max_radial) {
  const std::optional<double> radial = FitRadialTerm(x, y, rho_sq, huber_threshold, max_radial);
  if (!radial) return std::nullopt;
  return FitBrightnessTransferAtRadial(x, y, rho_sq, *radial, huber_threshold, max_gain_ratio);
}

RadialTermPool::RadialTermPool(int capacity) : capacity_(capacity) {
  Require(capacity >= 0, "RadialTermPool: capacity must be >= 0");
}

void RadialTermPool::Add(double keyframe_radial) {
  Require(std::isfinite(keyframe_radial), "RadialTermPool: a radial term must be finite");
  if (capacity_ == 0) return;
  fits_.push_back(keyframe_radial);
  if (static_cast<int>(fits_.size()) > capacity_) fits_.pop_front();
}

double RadialTermPool::MedianWith(double current) const {
  std::vector<double> values(fits_.begin(), fits_.end());
  values.push_back(current);
  return dvso::Median(std::move(values));
}

double RadialTermPool::Median() const {
  Require(!fits_.empty(), "RadialTermPool::Median: the pool is empty");
  return dvso::Median(std::vector<double>(fits_.begin(), fits_.end()));
}

double BrightnessTransferChange(const StereoBrightness& a, const StereoBrightness& b, double low, double high) {
  // The difference is bilinear in (I, rho^2): its largest magnitude is at a corner of [low, high] x [0, 1].
  double change = 0.0;
  for (double rho_sq : {0.0, 1.0}) {
    const double dg = b.Gain(rho_sq) - a.Gain(rho_sq), db = b.bias - a.bias;
    change = std::max({change, std::abs(dg * low + db), std::abs(dg * high + db)});
  }
  return change;
}

UnclippedRange UnclippedIntensityRange(const PyramidLevel& level) {
  Require(!level.data.empty(), "UnclippedIntensityRange: empty image");
  float lo = level.data[0][0], hi = lo;
  for (const Eigen::Vector3f& v : level.data) {
    lo = std::min(lo, v[0]);
    hi = std::max(hi, v[0]);
  }
  return UnclippedRange{lo + UnclippedRange::kClipMargin, hi - UnclippedRange::kClipMargin};
}

StereoBrightness EstimateStereoBrightness(const PyramidLevel& left, const PyramidLevel& right,
                                          const StereoBrightnessOptions& options) {
  StereoBrightness identity;
  if (!options.estimate) return identity;
  Require(left.width == right.width && left.height == right.height, "stereo images must have the same size");
  // The right camera sits at +baseline: a left pixel at x is seen at x - d on the right, so
  // the left image's left strip and the right image's right strip have no counterpart.
  const int border = static_cast<int>(options.border_fraction * left.width);
  const std::vector<float> l = SortedSamples(left, border, left.width, options.sample_step);
  const std::vector<float> r = SortedSamples(right, 0, right.width - border, options.sample_step);
  if (l.size() < 2 || r.size() < 2) return identity;

  // Quantile pairs; a level where either image is clipped (equal to its extreme
  // value: black or saturated) carries no information about the transfer.
  std::vector<double> x, y;  // quantiles of the left and the right image
  for (int k = 0; k < options.num_quantiles; ++k) {
    const double q =
        options.min_quantile + (options.max_quantile - options.min_quantile) * k / (options.num_quantiles - 1);
    const float lq = Quantile(l, q), rq = Quantile(r, q);
    if (lq <= l.front() || lq >= l.back() || rq <= r.front() || rq >= r.back()) continue;
    x.push_back(lq);
    y.push_back(rq);
  }

  return FitBrightnessTransfer(x, y, options.huber_threshold, options.max_gain_ratio).value_or(identity);
}

}  // namespace dvso::vo
