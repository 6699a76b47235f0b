#include "core/depth_ranges.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>

#include "core/error.h"
#include "core/eval_depth.h"

namespace dvso {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

}  // namespace

cv::Mat TexturedPixelMask(const cv::Mat& grey, double min_gradient) {
  Require(grey.type() == CV_8U, "TexturedPixelMask expects an 8-bit grey image");
  Require(std::isfinite(min_gradient) && min_gradient >= 0.0, "TexturedPixelMask: min_gradient must be >= 0");
  cv::Mat gx, gy, magnitude;
  cv::Sobel(grey, gx, CV_32F, 1, 0);
  cv::Sobel(grey, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, magnitude);
  cv::Mat mask;
  cv::compare(magnitude, min_gradient, mask, cv::CMP_GE);
  return mask;
}

void CheckDepthRangeEdges(const std::vector<double>& edges) {
  Require(edges.size() >= 2, "depth ranges need at least two edges");
  for (size_t i = 0; i < edges.size(); ++i) {
    Require(std::isfinite(edges[i]) && edges[i] >= 0.0, "depth range edges must be finite and >= 0");
    if (i > 0) Require(edges[i] > edges[i - 1], "depth range edges must increase");
  }
}

DepthRangeAccumulator::DepthRangeAccumulator(std::vector<double> edges) : edges_(std::move(edges)) {
  CheckDepthRangeEdges(edges_);
  Sums empty;
  empty.log_ratio_histogram.assign(kHistogramBins, 0);
  ranges_.assign(edges_.size() - 1, empty);
  overall_ = empty;
}

void DepthRangeAccumulator::Accumulate(Sums* sums, double pred, double gt) const {
  ++sums->pixels;
  sums->abs_rel += std::abs(pred - gt) / gt;
  sums->a1 += std::max(pred / gt, gt / pred) < kDeltaThreshold;
  const double log_ratio = std::clamp(std::log(pred / gt), -kLogRatioLimit, kLogRatioLimit);
  const int bin = static_cast<int>(std::lround((log_ratio + kLogRatioLimit) / kLogRatioBin));
  ++sums->log_ratio_histogram[std::clamp(bin, 0, kHistogramBins - 1)];
}

void DepthRangeAccumulator::Add(const cv::Mat& pred_depth, const cv::Mat& gt_depth, const cv::Mat& mask,
                                const DepthEvalOptions& options, double scale) {
  Require(std::isfinite(scale) && scale > 0.0, "depth ranges: the scale must be > 0");
  ForEachEvaluatedPixel(pred_depth, gt_depth, mask, options, [&](double gt, double raw_pred) {
    if (gt < edges_.front() || gt >= edges_.back()) return;
    const double pred = ClampPredictedDepth(scale * raw_pred, options);
    const size_t range = std::upper_bound(edges_.begin(), edges_.end(), gt) - edges_.begin() - 1;
    Accumulate(&ranges_[range], pred, gt);
    Accumulate(&overall_, pred, gt);
  });
}

DepthRangeStats DepthRangeAccumulator::Finish(const Sums& sums, double min_depth, double max_depth) const {
  DepthRangeStats stats;
  stats.min_depth = min_depth;
  stats.max_depth = max_depth;
  stats.pixels = sums.pixels;
  if (sums.pixels == 0) {
    stats.abs_rel = stats.a1 = stats.median_pred_over_gt = kNaN;
    return stats;
  }
  stats.abs_rel = sums.abs_rel / sums.pixels;
  stats.a1 = static_cast<double>(sums.a1) / sums.pixels;
  // Lower median: the value of rank ceil(n / 2) in increasing order.
  const long rank = (sums.pixels + 1) / 2;
  long seen = 0;
  for (size_t bin = 0; bin < sums.log_ratio_histogram.size(); ++bin) {
    seen += sums.log_ratio_histogram[bin];
    if (seen >= rank) {
      stats.median_pred_over_gt = std::exp(static_cast<double>(bin) * kLogRatioBin - kLogRatioLimit);
      break;
    }
  }
  return stats;
}

std::vector<DepthRangeStats> DepthRangeAccumulator::Ranges() const {
  std::vector<DepthRangeStats> out;
  for (size_t i = 0; i < ranges_.size(); ++i) out.push_back(Finish(ranges_[i], edges_[i], edges_[i + 1]));
  return out;
}

DepthRangeStats DepthRangeAccumulator::Overall() const { return Finish(overall_, edges_.front(), edges_.back()); }

}  // namespace dvso
