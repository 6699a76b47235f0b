#include "sdso_labels/stereo_check.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.h"

namespace dvso::labels {

namespace {
constexpr float kNoMatch = 2.0f;  // cost of a window without texture (1 - ZNCC is in [0, 2])
}  // namespace

void StereoCheckOptions::Check() const {
  Require(window_radius >= 1 && window_radius <= 10, "labels: stereo_check.window_radius must be in [1, 10]");
  Require(max_offset > 0 && exclusion >= max_offset, "labels: stereo_check needs 0 < max_offset <= exclusion");
  Require(min_cost_gap >= 0 && max_cost > 0, "labels: stereo_check thresholds must be positive");
  Require(max_disparity >= 1, "labels: stereo_check.max_disparity must be >= 1");
  Require(edge_shift >= 0 && edge_shift <= 10, "labels: stereo_check.edge_shift must be in [0, 10]");
  Require(edge_max_cost > 0, "labels: stereo_check.edge_max_cost must be > 0");
  Require(edge_distinct_gap >= 0 && edge_distinct_gap < kNoMatch,
          "labels: stereo_check.edge_distinct_gap must be in [0, 2)");
}

namespace {

constexpr float kMinVariance = 1e-3f;  // windows with less intensity variance are textureless
// px from the label at which a shifted window's competing matches are taken (edge_distinct_gap):
// beyond the sub-pixel uncertainty of a right label, within the reach of a silhouette's error.
constexpr int kEdgeCompetitorOffsets[] = {2, 3, 4};

// 1 - ZNCC between the window of `left` at (x, y) and the window of `right`
// at (x - d, y) (d < 0 searches to the right: used by the left-right check).
float MatchCost(const cv::Mat& left, const cv::Mat& right, int x, int y, int d, int r, float left_mean,
                float left_norm) {
  const int xr = x - d;
  float sum = 0, sum_sq = 0, cross = 0;
  const int n = (2 * r + 1) * (2 * r + 1);
  for (int dy = -r; dy <= r; ++dy) {
    const float* l = left.ptr<float>(y + dy);
    const float* q = right.ptr<float>(y + dy);
    for (int dx = -r; dx <= r; ++dx) {
      const float v = q[xr + dx];
      sum += v;
      sum_sq += v * v;
      cross += (l[x + dx] - left_mean) * v;
    }
  }
  const float right_var = sum_sq - sum * sum / n;
  if (right_var <= kMinVariance || left_norm <= 1e-3f) return kNoMatch;
  return 1.0f - cross / (left_norm * std::sqrt(right_var));
}

// Mean and centred norm of the window of `image` at (x, y).
void WindowStatistics(const cv::Mat& image, int x, int y, int r, float* mean, float* norm) {
  const int n = (2 * r + 1) * (2 * r + 1);
  float sum = 0, sum_sq = 0;
  for (int dy = -r; dy <= r; ++dy) {
    const float* row = image.ptr<float>(y + dy);
    for (int dx = -r; dx <= r; ++dx) {
      sum += row[x + dx];
      sum_sq += row[x + dx] * row[x + dx];
    }
  }
  *mean = sum / n;
  *norm = std::sqrt(std::max(0.f, sum_sq - sum * *mean));
}

// Sub-pixel minimum of costs[0..n) around its discrete minimum `best`.
double SubPixelMinimum(const std::vector<float>& costs, int best) {
  if (best <= 0 || best + 1 >= static_cast<int>(costs.size())) return best;
  const double c0 = costs[best - 1], c1 = costs[best], c2 = costs[best + 1];
  const double denom = c0 - 2 * c1 + c2;
  return denom > 1e-9 ? best + 0.5 * (c0 - c2) / denom : best;
}

// Window means (centred around 0, as the float images) and norms
// sqrt(sum (I - mean)^2) of every pixel of an 8-bit image; the sums are exact
// integers (border pixels are never queried).
void WindowMeanAndNorm(const cv::Mat& image8, int r, cv::Mat* mean, cv::Mat* norm) {
  cv::Mat squares, sum, sum_sq;
  image8.convertTo(squares, CV_16U);
  squares = squares.mul(squares);  // <= 255^2, fits in 16 bits
  const cv::Size window(2 * r + 1, 2 * r + 1);
  cv::boxFilter(image8, sum, CV_32S, window, cv::Point(-1, -1), false, cv::BORDER_REPLICATE);
  cv::boxFilter(squares, sum_sq, CV_32S, window, cv::Point(-1, -1), false, cv::BORDER_REPLICATE);
  const int n = window.area();
  *mean = cv::Mat(image8.size(), CV_32F);
  *norm = cv::Mat(image8.size(), CV_32F);
  // n * sum (I - mean)^2 = n * sum I^2 - (sum I)^2: both terms are below
  // n^2 * 255^2, i.e. exact in 32-bit integers up to 13x13 windows.
  const bool fits_int32 = static_cast<int64_t>(n) * n * 255 * 255 < (int64_t{1} << 31);
  const float inv_n = 1.0f / n;
  for (int y = 0; y < image8.rows; ++y) {
    const int* s = sum.ptr<int>(y);
    const int* q = sum_sq.ptr<int>(y);
    float* m = mean->ptr<float>(y);
    float* v = norm->ptr<float>(y);
    for (int x = 0; x < image8.cols; ++x) m[x] = static_cast<float>(s[x]) * inv_n - 128.0f;
    if (fits_int32) {
      for (int x = 0; x < image8.cols; ++x) {
        const int scaled = n * q[x] - s[x] * s[x];
        v[x] = std::sqrt(static_cast<float>(scaled) * inv_n);
      }
    } else {
      for (int x = 0; x < image8.cols; ++x) {
        const int64_t scaled = static_cast<int64_t>(n) * q[x] - static_cast<int64_t>(s[x]) * s[x];
        v[x] = static_cast<float>(std::sqrt(static_cast<double>(scaled) / n));
      }
    }
  }
}

// cross[k] += sum_t weights[t] * other[k + t], k < n: one window row correlated
// with every position of a row. kTaps is a compile-time constant so the tap
// loop unrolls and the loop over k vectorises.
template <int kTaps>
void CorrelateRow(const float* weights, const float* other, int n, float* cross) {
  for (int k = 0; k < n; ++k) {
    float acc = 0.f;
    for (int t = 0; t < kTaps; ++t) acc += weights[t] * other[k + t];
    cross[k] += acc;
  }
}

void CorrelateRowAnyTaps(const float* weights, int taps, const float* other, int n, float* cross) {
  switch (taps) {
    case 3: return CorrelateRow<3>(weights, other, n, cross);
    case 5: return CorrelateRow<5>(weights, other, n, cross);
    case 7: return CorrelateRow<7>(weights, other, n, cross);
    case 9: return CorrelateRow<9>(weights, other, n, cross);
    case 11: return CorrelateRow<11>(weights, other, n, cross);
    default:
      for (int k = 0; k < n; ++k) {
        float acc = 0.f;
        for (int t = 0; t < taps; ++t) acc += weights[t] * other[k + t];
        cross[k] += acc;
      }
  }
}

// Index of the first smallest cost.
int ArgMin(const std::vector<float>& costs) {
  return static_cast<int>(std::min_element(costs.begin(), costs.end()) - costs.begin());
}

// The best match (discrete index `best`, sub-pixel `best_sub`) is good and
// unique: low cost, and every match farther than `exclusion` is clearly worse.
bool IsUnique(const std::vector<float>& costs, int best, double best_sub, const StereoCheckOptions& options) {
  if (costs[best] > options.max_cost) return false;
  if (options.min_cost_gap <= 0) return true;  // `best` is the global minimum: no competitor is better
  float competitor = kNoMatch;
  for (int d = 0; d < static_cast<int>(costs.size()); ++d) {
    if (std::abs(d - best_sub) > options.exclusion) competitor = std::min(competitor, costs[d]);
  }
  return competitor - costs[best] >= options.min_cost_gap;
}

}  // namespace

StereoLabelChecker::StereoLabelChecker(const cv::Mat& left8, const cv::Mat& right8, const StereoCheckOptions& options)
    : options_(options) {
  Require(left8.type() == CV_8UC1 && right8.type() == CV_8UC1 && left8.size() == right8.size(),
          "stereo check needs a grey 8-bit pair of one size");
  options_.Check();
  left8.convertTo(left_, CV_32F, 1.0, -128.0);
  right8.convertTo(right_, CV_32F, 1.0, -128.0);
  WindowMeanAndNorm(left8, options_.window_radius, &left_mean_, &left_norm_);
  WindowMeanAndNorm(right8, options_.window_radius, &right_mean_, &right_norm_);
}

void StereoLabelChecker::ScanCosts(const cv::Mat& fixed, const cv::Mat& fixed_mean, const cv::Mat& fixed_norm,
                                   const cv::Mat& other, const cv::Mat& other_norm, int x, int y, int x_begin,
                                   int x_end, std::vector<float>* costs) {
  const int r = options_.window_radius;
  const int n = x_end - x_begin;
  costs->assign(n, kNoMatch);
  const float norm = fixed_norm.at<float>(y, x);
  if (norm * norm <= kMinVariance) return;
  const float mean = fixed_mean.at<float>(y, x);
  cross_.assign(n, 0.f);
  const int taps = 2 * r + 1;
  weights_.resize(taps);
  // Cross-correlation of the centred fixed window with every window of the
  // other row: sum (f - mean_f) * o == sum (f - mean_f) * (o - mean_o).
  for (int dy = -r; dy <= r; ++dy) {
    const float* f = fixed.ptr<float>(y + dy) + x - r;
    for (int t = 0; t < taps; ++t) weights_[t] = f[t] - mean;
    CorrelateRowAnyTaps(weights_.data(), taps, other.ptr<float>(y + dy) + x_begin - r, n, cross_.data());
  }
  const float* other_norm_row = other_norm.ptr<float>(y) + x_begin;
  for (int k = 0; k < n; ++k) {
    const float on = other_norm_row[k];
    if (on * on > kMinVariance) (*costs)[k] = 1.0f - cross_[k] / (norm * on);
  }
}

float StereoLabelChecker::CostAt(int x, int y, float disparity) const {
  const int r = options_.window_radius;
  const int d0 = static_cast<int>(std::floor(disparity));
  const float frac = disparity - d0;
  if (x - d0 - 1 < r || x - d0 >= left_.cols - r) return kNoMatch;
  const float norm = left_norm_.at<float>(y, x);
  if (norm * norm <= kMinVariance) return kNoMatch;
  const float mean = left_mean_.at<float>(y, x);
  float cross0 = 0.f, cross1 = 0.f;  // at d0 and d0 + 1
  for (int dy = -r; dy <= r; ++dy) {
    const float* f = left_.ptr<float>(y + dy);
    const float* o = right_.ptr<float>(y + dy);
    for (int dx = -r; dx <= r; ++dx) {
      const float w = f[x + dx] - mean;
      cross0 += w * o[x - d0 + dx];
      cross1 += w * o[x - d0 - 1 + dx];
    }
  }
  const float n0 = right_norm_.at<float>(y, x - d0), n1 = right_norm_.at<float>(y, x - d0 - 1);
  const float c0 = n0 * n0 > kMinVariance ? 1.0f - cross0 / (norm * n0) : kNoMatch;
  const float c1 = n1 * n1 > kMinVariance ? 1.0f - cross1 / (norm * n1) : kNoMatch;
  return (1.0f - frac) * c0 + frac * c1;
}

int StereoLabelChecker::ScanFullRange(int x, int y, int max_d) {
  // Right window centres x - max_d .. x; costs_[d] belongs to centre x - d.
  ScanCosts(left_, left_mean_, left_norm_, right_, right_norm_, x, y, x - max_d, x + 1, &back_costs_);
  costs_.resize(max_d + 1);
  for (int d = 0; d <= max_d; ++d) costs_[d] = back_costs_[max_d - d];
  return ArgMin(costs_);
}

double StereoLabelChecker::BestDisparity(int x, int y) {
  const int r = options_.window_radius;
  if (y < r || y >= left_.rows - r || x < r || x >= left_.cols - r) return -1.0;
  const int max_d = std::min(x - r, options_.max_disparity);
  if (max_d < 0) return -1.0;
  const int best = ScanFullRange(x, y, max_d);
  if (costs_[best] >= kNoMatch) return -1.0;
  return SubPixelMinimum(costs_, best);
}

bool StereoLabelChecker::Keep(int x, int y, float label) {
  const int r = options_.window_radius;
  if (!(label > 0) || y < r || y >= left_.rows - r || x < r || x >= left_.cols - r) return false;
  // Every integer disparity whose right window fits in the image.
  const int max_d = std::min(x - r, options_.max_disparity);
  if (max_d < 0 || label > max_d + options_.max_offset) return false;
  // Pre-test on a band of disparities around the label: if the best match
  // inside the band misses the label, so does the best over the full range
  // (which is either the same match or lies outside the band), so most wrong
  // labels are rejected without the full scan.
  const int band = static_cast<int>(std::ceil(options_.max_offset)) + 2;
  const int band_low = std::max(0, static_cast<int>(std::floor(label)) - band);
  const int band_high = std::min(max_d, static_cast<int>(std::ceil(label)) + band);
  if (band_high - band_low < max_d) {
    ScanCosts(left_, left_mean_, left_norm_, right_, right_norm_, x, y, x - band_high, x - band_low + 1, &back_costs_);
    costs_.resize(band_high - band_low + 1);
    for (int d = band_low; d <= band_high; ++d) costs_[d - band_low] = back_costs_[band_high - d];
    const int band_best = ArgMin(costs_);
    if (costs_[band_best] > options_.max_cost) return false;
    if (std::abs(band_low + SubPixelMinimum(costs_, band_best) - label) > options_.max_offset) return false;
  }
  // Depth edges: the shifted windows must match at the label too.
  if (const int e = options_.edge_shift; e > 0) {
    const int shifts[4][2] = {{-e, 0}, {e, 0}, {0, -e}, {0, e}};
    for (const auto& s : shifts) {
      const int xs = x + s[0], ys = y + s[1];
      if (ys < r || ys >= left_.rows - r || xs < r || xs >= left_.cols - r) return false;
      const float cost = CostAt(xs, ys, label);
      if (cost <= options_.edge_max_cost) continue;
      // The escape needs a match at all (the centred window's max_cost) and competitors that
      // were measured: a disparity whose window leaves the image is no evidence either way.
      if (options_.edge_distinct_gap <= 0 || cost > options_.max_cost) return false;
      float competitor = kNoMatch;
      for (const int k : kEdgeCompetitorOffsets) {
        for (const float c : {CostAt(xs, ys, label - k), CostAt(xs, ys, label + k)}) {
          if (c < kNoMatch) competitor = std::min(competitor, c);
        }
      }
      if (competitor >= kNoMatch || competitor - cost < options_.edge_distinct_gap) return false;
    }
  }
  const int best = ScanFullRange(x, y, max_d);
  const double best_sub = SubPixelMinimum(costs_, best);
  if (std::abs(best_sub - label) > options_.max_offset) return false;
  if (!IsUnique(costs_, best, best_sub, options_)) return false;
  if (!options_.left_right_check) return true;
  // Match the right pixel back into the left image: x_left = x_right + d'.
  const int xr = x - best;
  const int max_back = std::min(left_.cols - 1 - r - xr, options_.max_disparity);
  if (xr < r || max_back < 0) return false;
  ScanCosts(right_, right_mean_, right_norm_, left_, left_norm_, xr, y, xr, xr + max_back + 1, &back_costs_);
  const int back_best = ArgMin(back_costs_);
  return std::abs(SubPixelMinimum(back_costs_, back_best) - best_sub) <= options_.max_offset;
}

int VerifyLabelsWithStereo(const cv::Mat& left8, const cv::Mat& right8, const StereoCheckOptions& options,
                           cv::Mat* labels) {
  Require(labels->size() == left8.size() && labels->type() == CV_32FC1,
          "stereo check needs a CV_32F label map of the images' size");
  if (!options.enabled) return cv::countNonZero(*labels > 0);
  StereoLabelChecker checker(left8, right8, options);
  int kept = 0;
  for (int y = 0; y < labels->rows; ++y) {
    float* row = labels->ptr<float>(y);
    for (int x = 0; x < labels->cols; ++x) {
      if (!(row[x] > 0)) continue;
      if (checker.Keep(x, y, row[x])) {
        ++kept;
      } else {
        row[x] = 0;
      }
    }
  }
  return kept;
}

int VerifyRightLabelsWithStereo(const cv::Mat& left8, const cv::Mat& right8, const StereoCheckOptions& options,
                                cv::Mat* right_labels) {
  // Mirroring x -> W-1-x turns "right x matches left x + d" into "mirrored-right
  // x' matches mirrored-left x' - d": the left-image test with the roles swapped.
  cv::Mat mirrored_left, mirrored_right, mirrored_labels;
  cv::flip(left8, mirrored_left, 1);
  cv::flip(right8, mirrored_right, 1);
  cv::flip(*right_labels, mirrored_labels, 1);
  const int kept = VerifyLabelsWithStereo(mirrored_right, mirrored_left, options, &mirrored_labels);
  cv::flip(mirrored_labels, *right_labels, 1);
  return kept;
}

int VerifyLabelsWithStereoReference(const cv::Mat& left8, const cv::Mat& right8, const StereoCheckOptions& options,
                           cv::Mat* labels) {
  Require(left8.type() == CV_8UC1 && right8.type() == CV_8UC1 && left8.size() == right8.size() &&
              labels->size() == left8.size() && labels->type() == CV_32FC1,
          "stereo check needs grey 8-bit images of the label map's size");
  if (!options.enabled) return cv::countNonZero(*labels > 0);
  cv::Mat left, right;
  left8.convertTo(left, CV_32F);
  right8.convertTo(right, CV_32F);
  const int r = options.window_radius;
  std::vector<float> costs, back_costs;
  int kept = 0;
  for (int y = 0; y < labels->rows; ++y) {
    float* row = labels->ptr<float>(y);
    for (int x = 0; x < labels->cols; ++x) {
      const float label = row[x];
      if (!(label > 0)) continue;
      row[x] = 0;
      if (y < r || y >= labels->rows - r || x < r || x >= labels->cols - r) continue;
      float mean = 0, norm = 0;
      WindowStatistics(left, x, y, r, &mean, &norm);
      // Every integer disparity whose right window fits in the image.
      const int max_d = std::min(x - r, options.max_disparity);
      if (max_d < 0 || label > max_d + options.max_offset) continue;
      costs.assign(max_d + 1, kNoMatch);
      int best = 0;
      for (int d = 0; d <= max_d; ++d) {
        costs[d] = MatchCost(left, right, x, y, d, r, mean, norm);
        if (costs[d] < costs[best]) best = d;
      }
      const double best_sub = SubPixelMinimum(costs, best);
      if (costs[best] > options.max_cost || std::abs(best_sub - label) > options.max_offset) continue;
      float competitor = kNoMatch;
      for (int d = 0; d <= max_d; ++d) {
        if (std::abs(d - best_sub) > options.exclusion) competitor = std::min(competitor, costs[d]);
      }
      if (competitor - costs[best] < options.min_cost_gap) continue;
      if (options.left_right_check) {
        // Match the right pixel back into the left image: x_left = x_right + d'.
        const int xr = x - best;
        const int max_back = std::min(left.cols - 1 - r - xr, options.max_disparity);
        if (xr < r || max_back < 0) continue;
        float right_mean = 0, right_norm = 0;
        WindowStatistics(right, xr, y, r, &right_mean, &right_norm);
        back_costs.assign(max_back + 1, kNoMatch);
        int back_best = 0;
        for (int d = 0; d <= max_back; ++d) {
          back_costs[d] = MatchCost(right, left, xr, y, -d, r, right_mean, right_norm);
          if (back_costs[d] < back_costs[back_best]) back_best = d;
        }
        if (std::abs(SubPixelMinimum(back_costs, back_best) - best_sub) > options.max_offset) continue;
      }
      row[x] = label;
      ++kept;
    }
  }
  return kept;
}

}  // namespace dvso::labels
