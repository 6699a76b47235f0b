// Single-image depth accuracy as in Eigen et al. (NIPS 2014) and monodepth
// (Godard et al. CVPR 2017): abs rel, sq rel, RMSE, RMSE log and the
// threshold accuracies delta < 1.25^k, per image, then averaged over images.
// Formulas and masking rules: docs/evaluation.md.
#pragma once

#include <nlohmann/json.hpp>
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/depth_ranges.h"

namespace dvso {

enum class MapKind { kDepth, kDisparity };
enum class DepthCrop { kNone, kEigen, kGarg };

// "depth" | "disparity"; "none" | "eigen" | "garg". Throw dvso::Error otherwise.
MapKind ParseMapKind(const std::string& name);
DepthCrop ParseDepthCrop(const std::string& name);
std::string MapKindName(MapKind kind);
std::string DepthCropName(DepthCrop crop);

struct DepthEvalOptions {
  MapKind pred_kind = MapKind::kDisparity;  // predictions: disparity (px) or depth (m)
  MapKind gt_kind = MapKind::kDisparity;    // ground truth: disparity (px, KITTI disp_occ) or depth (m)
  double fxb = 0.0;            // focal length (px, at GT resolution) * baseline (m); needed for disparities
  bool kitti_focal_by_width = false;  // instead of fxb: KITTI focal length from the GT width, baseline 0.54 m
  // Split evaluation only, instead of fxb: each split line's fx * baseline from its drive's calibration under
  // this KITTI raw root (SplitLineFxB; monodepth's Eigen-split conversion).
  std::string raw_root;
  DepthCrop crop = DepthCrop::kNone;  // evaluation crop of Eigen et al. or Garg et al. (fractions of GT size)
  double min_depth = 1e-3;     // GT kept when > min_depth; predictions clamped up to it (m)
  double max_depth = 80.0;     // GT kept when < max_depth; predictions clamped down to it (m)
  bool median_scaling = false; // scale predictions by median(gt) / median(pred) per image (monocular)
  // Optional breakdown by GT depth range (core/depth_ranges.h), pixels pooled over images; empty = none.
  std::vector<double> range_edges;
  // Breakdown only: count only pixels whose grey image gradient (Sobel magnitude) is >= this, the kind of
  // pixel DSO selects; needs image_dir (folder evaluation: images named like the GT maps, GT size). The
  // main metrics always use every valid GT pixel (the standard protocol).
  double min_image_gradient = 0.0;
  std::string image_dir;

  // Throws dvso::Error on invalid values (e.g. a disparity kind without fxb).
  void Check() const;
};

// Whether predictions or GT are disparities: only then is fx * baseline (fxb, the KITTI width table or the
// raw root's calibration) looked up, used and reported.
bool ConvertsDisparity(const DepthEvalOptions& options);

struct DepthMetrics {
  double abs_rel = 0.0;   // mean |d - d*| / d*
  double sq_rel = 0.0;    // mean (d - d*)^2 / d*
  double rmse = 0.0;      // sqrt(mean (d - d*)^2), metres
  double rmse_log = 0.0;  // sqrt(mean (log d - log d*)^2)
  double a1 = 0.0;        // fraction with max(d/d*, d*/d) < 1.25
  double a2 = 0.0;        // ... < 1.25^2
  double a3 = 0.0;        // ... < 1.25^3
  long valid_pixels = 0;  // pixels evaluated (sum over images for aggregates)
  double scale = 1.0;     // median-scaling factor applied (1 without; mean over images for aggregates)
};

// KITTI rectified focal length (px) of the raw-data calibration days, keyed by
// image width (the table monodepth uses for the KITTI 2015 training images).
// Throws dvso::Error for any other width.
double KittiFocalLengthForWidth(int width);
constexpr double kKittiStereoBaseline = 0.54;  // metres, the value monodepth's evaluation uses

// Rows [floor(r0 H), floor(r1 H)), columns [floor(c0 W), floor(c1 W)) with the
// crop fractions of monodepth's evaluation; the whole image for kNone.
cv::Rect DepthCropRegion(DepthCrop crop, int width, int height);

// Resizes a prediction (CV_32F) to the GT size with bilinear interpolation;
// disparities are multiplied by gt_width / pred_width (a disparity is a width).
cv::Mat ResizePrediction(const cv::Mat& prediction, MapKind kind, cv::Size gt_size);

// depth = fxb / disparity. Non-positive disparities become `nonpositive_value`
// (0 = invalid for GT; +inf = "infinitely far" for predictions, later clamped).
cv::Mat DisparityToDepth(const cv::Mat& disparity, double fxb, float nonpositive_value);

constexpr double kDeltaThreshold = 1.25;  // a1 = share with max(d / d*, d* / d) < 1.25 (a2, a3: its powers)

// The pixels every depth statistic uses: inside the crop, mask != 0 (an empty mask keeps all), GT finite
// and strictly inside (min_depth, max_depth). Calls visit(gt, pred) with the unclamped prediction;
// throws dvso::Error naming the pixel when the prediction there is NaN. Maps: CV_32F, equal size.
void ForEachEvaluatedPixel(const cv::Mat& pred_depth, const cv::Mat& gt_depth, const cv::Mat& mask,
                           const DepthEvalOptions& options, const std::function<void(double gt, double pred)>& visit);

// A prediction clamped to [min_depth, max_depth] (after any scaling), as monodepth2's evaluation does.
double ClampPredictedDepth(double depth, const DepthEvalOptions& options);

// Metrics of one image: pred_depth and gt_depth are CV_32F depths (m) of equal
// size; GT pixels <= 0 or non-finite are invalid. Applies the crop, the GT
// range mask, median scaling and the clamping of predictions (in that order).
// valid_pixels == 0 (and all metrics NaN) when no GT pixel survives the mask.
DepthMetrics ComputeDepthMetrics(const cv::Mat& pred_depth, const cv::Mat& gt_depth,
                                 const DepthEvalOptions& options);

struct DepthEvalResult {
  std::vector<std::string> names;          // evaluated file names, sorted
  std::vector<DepthMetrics> per_image;     // same order as names
  std::vector<std::string> skipped;        // files without any valid GT pixel (excluded from the mean)
  DepthMetrics mean;                       // arithmetic mean over evaluated images
  std::vector<DepthRangeStats> ranges;     // per GT depth range (options.range_edges; empty without)
  DepthRangeStats all_ranges;              // the pixels of all ranges together (pixels == 0 without)
};

// Evaluates every *.png of gt_dir against the same name in pred_dir (KITTI
// uint16 maps, value / 256). Throws dvso::Error naming the files when a folder
// is empty, the names differ, or no image has a valid GT pixel.
DepthEvalResult EvaluateDepthFolders(const std::string& pred_dir, const std::string& gt_dir,
                                     const DepthEvalOptions& options);

// fx * baseline (px m) that turns camera `camera`'s (2 or 3) disparities into depth on the KITTI raw day of
// `calibration`, as monodepth's Eigen-split evaluation does (get_focal_length_baseline): fx = P_rect_0X[0][0],
// baseline = b3 - b2 of the colour pair with b_X = -P_rect_0X[0][3] / P_rect_0X[0][0] (2011_09_26:
// 721.5377 px x 0.5327 m, not the 0.54 m of the KITTI 2015 width table). Monodepth's formula on purpose (the
// paper's protocol): it leaves out the cameras' t.z, which the sequence readers count (RectifiedBaseline), a
// 0.003 % difference on 2011_09_26.
struct RawCameraCalibration;
double SplitLineFxB(const RawCameraCalibration& calibration, int camera);

// The paper's Eigen-split protocol on a split file (core/depth_split.h): GT maps gt_dir/%06d.png in
// split order (`dvso gt-depth --split`), predictions `pred` either a folder of %06d.png maps or an
// .npy stack (N, H, W) of disparities / width with one row per split line. Throws naming the split
// line or file for a missing map or a stack of another length.
DepthEvalResult EvaluateDepthSplit(const std::string& split_path, const std::string& pred, const std::string& gt_dir,
                                   const DepthEvalOptions& options);

// Mean over the given per-image metrics (images with valid_pixels == 0 are ignored).
DepthMetrics AverageDepthMetrics(const std::vector<DepthMetrics>& per_image);

nlohmann::json DepthEvalResultToJson(const DepthEvalResult& result, const DepthEvalOptions& options);
std::string FormatDepthEvalResult(const DepthEvalResult& result, const DepthEvalOptions& options);

}  // namespace dvso
