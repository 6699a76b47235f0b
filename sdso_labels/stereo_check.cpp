#include "sdso_labels/stereo_check.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.h"

namespace dvso::labels {

void StereoCheckOptions::Check() const {
  Require(window_radius >= 1 && window_radius <= 10, "labels: stereo_check.window_radius must be in [1, 10]");
  Require(max_offset > 0 && exclusion >= max_offset, "labels: stereo_check needs 0 < max_offset <= exclusion");
  Require(min_cost_gap >= 0 && max_cost > 0, "labels: stereo_check thresholds must be positive");
  Require(max_disparity >= 1, "labels: stereo_check.max_disparity must be >= 1");
}

namespace {

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
  if (right_var <= 1e-3f || left_norm <= 1e-3f) return 2.0f;
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

constexpr float kNoMatch = 2.0f;      // cost of a window without texture (1 - ZNCC is in [0, 2])
constexpr float kMinVariance = 1e-3f;  // windows with less intensity variance are textureless

// Window means and norms sqrt(sum (I - mean)^2) of every pixel (border
// pixels are never queried); sums in double so the variance keeps its digits.
void WindowMeanAndNorm(const cv::Mat& image, int r, cv::Mat* mean, cv::Mat* norm) {
  cv::Mat image64, sum, sum_sq;
  image.convertTo(image64, CV_64F);
  const cv::Size window(2 * r + 1, 2 * r + 1);
  cv::boxFilter(image64, sum, CV_64F, window, cv::Point(-1, -1), false, cv::BORDER_REPLICATE);
  cv::boxFilter(image64.mul(image64), sum_sq, CV_64F, window, cv::Point(-1, -1), false, cv::BORDER_REPLICATE);
  const double n = window.area();
  *mean = cv::Mat(image.size(), CV_32F);
  *norm = cv::Mat(image.size(), CV_32F);
  for (int y = 0; y < image.rows; ++y) {
    const double* s = sum.ptr<double>(y);
    const double* q = sum_sq.ptr<double>(y);
    float* m = mean->ptr<float>(y);
    float* v = norm->ptr<float>(y);
    for (int x = 0; x < image.cols; ++x) {
      m[x] = static_cast<float>(s[x] / n);
      v[x] = static_cast<float>(std::sqrt(std::max(0.0, q[x] - s[x] * s[x] / n)));
    }
  }
}

// The best match (discrete index `best`, sub-pixel `best_sub`) is good and
// unique: low cost, and every match farther than `exclusion` is clearly worse.
bool IsUnique(const std::vector<float>& costs, int best, double best_sub, const StereoCheckOptions& options) {
  if (costs[best] > options.max_cost) return false;
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
  WindowMeanAndNorm(left_, options_.window_radius, &left_mean_, &left_norm_);
  WindowMeanAndNorm(right_, options_.window_radius, &right_mean_, &right_norm_);
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
  float* cross = cross_.data();
  // Cross-correlation of the centred fixed window with every window of the
  // other row: sum (f - mean_f) * o == sum (f - mean_f) * (o - mean_o).
  for (int dy = -r; dy <= r; ++dy) {
    const float* f = fixed.ptr<float>(y + dy);
    const float* o = other.ptr<float>(y + dy) + x_begin;
    for (int dx = -r; dx <= r; ++dx) {
      const float w = f[x + dx] - mean;
      const float* od = o + dx;
      for (int k = 0; k < n; ++k) cross[k] += w * od[k];
    }
  }
  const float* other_norm_row = other_norm.ptr<float>(y) + x_begin;
  for (int k = 0; k < n; ++k) {
    const float on = other_norm_row[k];
    if (on * on > kMinVariance) (*costs)[k] = 1.0f - cross[k] / (norm * on);
  }
}

bool StereoLabelChecker::Keep(int x, int y, float label) {
  const int r = options_.window_radius;
  if (!(label > 0) || y < r || y >= left_.rows - r || x < r || x >= left_.cols - r) return false;
  // Every integer disparity whose right window fits in the image.
  const int max_d = std::min(x - r, options_.max_disparity);
  if (max_d < 0 || label > max_d + options_.max_offset) return false;
  // Right window centres x - max_d .. x; costs_[d] belongs to centre x - d.
  ScanCosts(left_, left_mean_, left_norm_, right_, right_norm_, x, y, x - max_d, x + 1, &back_costs_);
  costs_.resize(max_d + 1);
  for (int d = 0; d <= max_d; ++d) costs_[d] = back_costs_[max_d - d];
  const int best = static_cast<int>(std::min_element(costs_.begin(), costs_.end()) - costs_.begin());
  const double best_sub = SubPixelMinimum(costs_, best);
  if (std::abs(best_sub - label) > options_.max_offset) return false;
  if (!IsUnique(costs_, best, best_sub, options_)) return false;
  if (!options_.left_right_check) return true;
  // Match the right pixel back into the left image: x_left = x_right + d'.
  const int xr = x - best;
  const int max_back = std::min(left_.cols - 1 - r - xr, options_.max_disparity);
  if (xr < r || max_back < 0) return false;
  ScanCosts(right_, right_mean_, right_norm_, left_, left_norm_, xr, y, xr, xr + max_back + 1, &back_costs_);
  const int back_best =
      static_cast<int>(std::min_element(back_costs_.begin(), back_costs_.end()) - back_costs_.begin());
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
      costs.assign(max_d + 1, 2.0f);
      int best = 0;
      for (int d = 0; d <= max_d; ++d) {
        costs[d] = MatchCost(left, right, x, y, d, r, mean, norm);
        if (costs[d] < costs[best]) best = d;
      }
      const double best_sub = SubPixelMinimum(costs, best);
      if (costs[best] > options.max_cost || std::abs(best_sub - label) > options.max_offset) continue;
      float competitor = 2.0f;
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
        back_costs.assign(max_back + 1, 2.0f);
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
