// Depth error by ground-truth depth range, pooled over the pixels of all images, optionally only at
// textured pixels. Why: a per-image mean such as abs rel hides *where* a network is wrong and in which
// direction, and DVSO's metric scale follows the network's signed bias at the pixels DSO selects
// (strong image gradient), not its mean error: with the virtual baseline b_v and the training baseline
// b_train, DVSO's Sim3 scale is about (b_train / b_v) / median(pred / GT depth) over those pixels
// (docs/dvso.md, session 17; docs/evaluation.md).
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace dvso {

struct DepthEvalOptions;

// Statistics of one depth range [min_depth, max_depth) of the GT.
struct DepthRangeStats {
  double min_depth = 0.0;        // m, inclusive
  double max_depth = 0.0;        // m, exclusive
  long pixels = 0;               // GT pixels in the range (after crop, GT mask and texture mask)
  double abs_rel = 0.0;          // mean |d - d*| / d* over those pixels (pooled, not per image); NaN when empty
  double a1 = 0.0;               // share with max(d / d*, d* / d) < 1.25; NaN when empty
  double median_pred_over_gt = 0.0;  // median of d / d* (< 1: predicted too near); NaN when empty
};

// Grey image -> CV_8U mask, 255 where the 3x3 Sobel gradient magnitude sqrt(gx^2 + gy^2) (grey levels,
// OpenCV's unnormalised kernel, as DSO-style pixel selection sees edges) is >= min_gradient.
cv::Mat TexturedPixelMask(const cv::Mat& grey, double min_gradient);

// Throws dvso::Error unless edges are finite, >= 0, strictly increasing and at least two.
void CheckDepthRangeEdges(const std::vector<double>& edges);

// Accumulates pixels of many images into the ranges given by increasing edges (m, >= 0, at least two),
// plus one overall range [edges.front(), edges.back()). The median is taken from a histogram of
// log(d / d*) with bins of kLogRatioBin (a relative resolution of 0.05 %), so memory does not grow with
// the number of pixels.
class DepthRangeAccumulator {
 public:
  static constexpr double kLogRatioBin = 1e-3;    // histogram bin width in log(d / d*)
  static constexpr double kLogRatioLimit = 5.0;   // |log(d / d*)| beyond this falls into the end bins
  static constexpr int kHistogramBins = static_cast<int>(2 * kLogRatioLimit / kLogRatioBin + 0.5) + 1;

  explicit DepthRangeAccumulator(std::vector<double> edges);  // throws dvso::Error on invalid edges

  // pred_depth, gt_depth: CV_32F depths (m) of one image, equal size. mask: empty or CV_8U of that size
  // (0 = skip the pixel). The pixels of ComputeDepthMetrics (ForEachEvaluatedPixel), predictions
  // multiplied by `scale` (the image's median-scaling factor, 1 without), then ClampPredictedDepth.
  void Add(const cv::Mat& pred_depth, const cv::Mat& gt_depth, const cv::Mat& mask,
           const DepthEvalOptions& options, double scale = 1.0);

  std::vector<DepthRangeStats> Ranges() const;  // one per pair of consecutive edges
  DepthRangeStats Overall() const;              // all pixels of all ranges

 private:
  struct Sums {
    long pixels = 0;
    double abs_rel = 0.0;
    long a1 = 0;
    std::vector<long> log_ratio_histogram;
  };
  void Accumulate(Sums* sums, double pred, double gt) const;
  DepthRangeStats Finish(const Sums& sums, double min_depth, double max_depth) const;

  std::vector<double> edges_;
  std::vector<Sums> ranges_;
  Sums overall_;
};

}  // namespace dvso
