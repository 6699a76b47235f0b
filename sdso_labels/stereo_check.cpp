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

}  // namespace

int VerifyLabelsWithStereo(const cv::Mat& left8, const cv::Mat& right8, const StereoCheckOptions& options,
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
