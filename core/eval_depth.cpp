#include "core/eval_depth.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <limits>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <sstream>

#include "core/depth_split.h"
#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/kitti_raw_calibration.h"
#include "core/statistics.h"

namespace dvso {

namespace fs = std::filesystem;

namespace {

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Shortest decimal form ("5", "0.5", "12.25") for range names.
std::string FormatNumber(double value) {
  std::ostringstream s;
  s << value;
  return s.str();
}

}  // namespace

MapKind ParseMapKind(const std::string& name) {
  const std::string lower = Lower(name);
  if (lower == "depth") return MapKind::kDepth;
  if (lower == "disparity" || lower == "disp") return MapKind::kDisparity;
  throw Error("unknown map kind '" + name + "' (expected depth or disparity)");
}

DepthCrop ParseDepthCrop(const std::string& name) {
  const std::string lower = Lower(name);
  if (lower == "none") return DepthCrop::kNone;
  if (lower == "eigen") return DepthCrop::kEigen;
  if (lower == "garg") return DepthCrop::kGarg;
  throw Error("unknown crop '" + name + "' (expected none, eigen or garg)");
}

std::string MapKindName(MapKind kind) { return kind == MapKind::kDepth ? "depth" : "disparity"; }

std::string DepthCropName(DepthCrop crop) {
  switch (crop) {
    case DepthCrop::kNone: return "none";
    case DepthCrop::kEigen: return "eigen";
    case DepthCrop::kGarg: return "garg";
  }
  return "unknown";
}

void DepthEvalOptions::Check() const {
  Require(std::isfinite(min_depth) && min_depth > 0.0, "eval-depth: min_depth must be > 0");
  Require(std::isfinite(max_depth) && max_depth > min_depth, "eval-depth: max_depth must be > min_depth");
  Require(std::isfinite(fxb) && fxb >= 0.0, "eval-depth: fxb must be >= 0");
  Require((kitti_focal_by_width ? 1 : 0) + (fxb > 0.0 ? 1 : 0) + (raw_root.empty() ? 0 : 1) <= 1,
          "eval-depth: give only one of --fxb (or --calib), --kitti-focal and --raw-root");
  if (ConvertsDisparity(*this)) {
    Require(fxb > 0.0 || kitti_focal_by_width || !raw_root.empty(),
            "eval-depth: disparity maps need focal length * baseline (--fxb, --calib, --kitti-focal or, with "
            "--split, --raw-root) to become depths");
  }
  Require(std::isfinite(min_image_gradient) && min_image_gradient >= 0.0,
          "eval-depth: the minimum image gradient must be >= 0");
  Require(min_image_gradient == 0.0 || !image_dir.empty(),
          "eval-depth: a minimum image gradient needs the images (--images)");
  Require(image_dir.empty() || !range_edges.empty(),
          "eval-depth: images only select the pixels of the depth-range breakdown: give --ranges too");
  if (!range_edges.empty()) CheckDepthRangeEdges(range_edges);
}

bool ConvertsDisparity(const DepthEvalOptions& options) {
  return options.pred_kind == MapKind::kDisparity || options.gt_kind == MapKind::kDisparity;
}

double KittiFocalLengthForWidth(int width) {
  // P_rect_02[0][0] of the five KITTI raw calibration days (2011_09_26, 10_03, 09_28, 09_29, 09_30). Every
  // rectified camera of a day shares it: KITTI odometry 04-10 (2011_09_30, 1226 x 370) have P0[0][0] = 707.0912.
  // (708.2046, found in some tables for 1226, is a linear guess from the 1224 entry, not a calibration.)
  switch (width) {
    case 1242: return 721.5377;
    case 1241: return 718.856;
    case 1224: return 707.0493;
    case 1238: return 718.3351;
    case 1226: return 707.0912;
    default: break;
  }
  throw Error("no KITTI focal length known for image width " + std::to_string(width) +
              " (known: 1224, 1226, 1238, 1241, 1242); give --fxb instead");
}

cv::Rect DepthCropRegion(DepthCrop crop, int width, int height) {
  // Fractions of monodepth's evaluate_kitti.py, truncated like numpy's astype(int32).
  double r0 = 0, r1 = 1, c0 = 0, c1 = 1;
  if (crop == DepthCrop::kGarg) {
    r0 = 0.40810811, r1 = 0.99189189, c0 = 0.03594771, c1 = 0.96405229;
  } else if (crop == DepthCrop::kEigen) {
    r0 = 0.3324324, r1 = 0.91351351, c0 = 0.0359477, c1 = 0.96405229;
  } else {
    return cv::Rect(0, 0, width, height);
  }
  const int top = static_cast<int>(r0 * height), bottom = static_cast<int>(r1 * height);
  const int left = static_cast<int>(c0 * width), right = static_cast<int>(c1 * width);
  return cv::Rect(left, top, std::max(0, right - left), std::max(0, bottom - top));
}

cv::Mat ResizePrediction(const cv::Mat& prediction, MapKind kind, cv::Size gt_size) {
  Require(prediction.type() == CV_32F, "ResizePrediction expects a CV_32F map");
  if (prediction.size() == gt_size) return prediction.clone();
  cv::Mat resized;
  cv::resize(prediction, resized, gt_size, 0, 0, cv::INTER_LINEAR);
  if (kind == MapKind::kDisparity) resized *= static_cast<double>(gt_size.width) / prediction.cols;
  return resized;
}

cv::Mat DisparityToDepth(const cv::Mat& disparity, double fxb, float nonpositive_value) {
  Require(disparity.type() == CV_32F, "DisparityToDepth expects a CV_32F map");
  cv::Mat depth(disparity.size(), CV_32F);
  for (int v = 0; v < disparity.rows; ++v) {
    const float* d = disparity.ptr<float>(v);
    float* z = depth.ptr<float>(v);
    for (int u = 0; u < disparity.cols; ++u) {
      z[u] = (std::isfinite(d[u]) && d[u] > 0.0f) ? static_cast<float>(fxb / d[u]) : nonpositive_value;
    }
  }
  return depth;
}

void ForEachEvaluatedPixel(const cv::Mat& pred_depth, const cv::Mat& gt_depth, const cv::Mat& mask,
                           const DepthEvalOptions& options, const std::function<void(double gt, double pred)>& visit) {
  Require(pred_depth.type() == CV_32F && gt_depth.type() == CV_32F, "depth maps must be CV_32F");
  Require(pred_depth.size() == gt_depth.size(), "prediction and GT depth maps differ in size");
  Require(mask.empty() || (mask.type() == CV_8U && mask.size() == gt_depth.size()),
          "the pixel mask must be 8-bit and of the GT's size");
  const cv::Rect crop = DepthCropRegion(options.crop, gt_depth.cols, gt_depth.rows);
  for (int v = crop.y; v < crop.y + crop.height; ++v) {
    const float* g = gt_depth.ptr<float>(v);
    const float* p = pred_depth.ptr<float>(v);
    const uint8_t* m = mask.empty() ? nullptr : mask.ptr<uint8_t>(v);
    for (int u = crop.x; u < crop.x + crop.width; ++u) {
      if (m != nullptr && m[u] == 0) continue;
      if (!std::isfinite(g[u]) || g[u] <= options.min_depth || g[u] >= options.max_depth) continue;
      Require(!std::isnan(p[u]), "predicted depth is NaN at pixel (" + std::to_string(u) + ", " +
                                     std::to_string(v) + ")");
      visit(g[u], p[u]);  // +inf (zero disparity) is clamped to max_depth by ClampPredictedDepth
    }
  }
}

double ClampPredictedDepth(double depth, const DepthEvalOptions& options) {
  return std::min(std::max(depth, options.min_depth), options.max_depth);
}

DepthMetrics ComputeDepthMetrics(const cv::Mat& pred_depth, const cv::Mat& gt_depth,
                                 const DepthEvalOptions& options) {
  options.Check();
  std::vector<double> gt, pred;
  ForEachEvaluatedPixel(pred_depth, gt_depth, cv::Mat(), options, [&](double g, double p) {
    gt.push_back(g);
    pred.push_back(p);
  });
  DepthMetrics m;
  m.valid_pixels = static_cast<long>(gt.size());
  if (gt.empty()) {
    m.abs_rel = m.sq_rel = m.rmse = m.rmse_log = m.a1 = m.a2 = m.a3 = kNaN;
    return m;
  }
  if (options.median_scaling) {
    const double pred_median = Median(pred);
    Require(std::isfinite(pred_median) && pred_median > 0.0,
            "median scaling impossible: the median predicted depth is not a positive number");
    m.scale = Median(gt) / pred_median;
    for (double& p : pred) p *= m.scale;
  }
  double abs_rel = 0, sq_rel = 0, sq = 0, sq_log = 0;
  long a1 = 0, a2 = 0, a3 = 0;
  for (size_t i = 0; i < gt.size(); ++i) {
    const double d = ClampPredictedDepth(pred[i], options);
    const double g = gt[i];
    const double diff = d - g;
    abs_rel += std::abs(diff) / g;
    sq_rel += diff * diff / g;
    sq += diff * diff;
    const double log_diff = std::log(d) - std::log(g);
    sq_log += log_diff * log_diff;
    const double ratio = std::max(d / g, g / d);
    a1 += ratio < kDeltaThreshold;
    a2 += ratio < kDeltaThreshold * kDeltaThreshold;
    a3 += ratio < kDeltaThreshold * kDeltaThreshold * kDeltaThreshold;
  }
  const double n = static_cast<double>(gt.size());
  m.abs_rel = abs_rel / n;
  m.sq_rel = sq_rel / n;
  m.rmse = std::sqrt(sq / n);
  m.rmse_log = std::sqrt(sq_log / n);
  m.a1 = a1 / n;
  m.a2 = a2 / n;
  m.a3 = a3 / n;
  return m;
}

DepthMetrics AverageDepthMetrics(const std::vector<DepthMetrics>& per_image) {
  DepthMetrics mean;
  mean.scale = 0.0;
  int count = 0;
  for (const DepthMetrics& m : per_image) {
    if (m.valid_pixels == 0) continue;
    mean.abs_rel += m.abs_rel;
    mean.sq_rel += m.sq_rel;
    mean.rmse += m.rmse;
    mean.rmse_log += m.rmse_log;
    mean.a1 += m.a1;
    mean.a2 += m.a2;
    mean.a3 += m.a3;
    mean.scale += m.scale;
    mean.valid_pixels += m.valid_pixels;
    ++count;
  }
  Require(count > 0, "no image has a valid ground-truth pixel inside the crop and depth range");
  for (double* v : {&mean.abs_rel, &mean.sq_rel, &mean.rmse, &mean.rmse_log, &mean.a1, &mean.a2, &mean.a3,
                    &mean.scale}) {
    *v /= count;
  }
  return mean;
}

namespace {

std::vector<std::string> ListPngNames(const std::string& dir) {
  RequireFile(fs::is_directory(dir), dir, "not a directory");
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (!entry.is_regular_file()) continue;
    if (Lower(entry.path().extension().string()) != ".png" || IsUnfinishedAtomicWrite(entry.path())) continue;
    names.push_back(entry.path().filename().string());
  }
  std::sort(names.begin(), names.end());
  RequireFile(!names.empty(), dir, "holds no .png maps");
  return names;
}

std::string JoinFirst(const std::vector<std::string>& names, size_t max_count) {
  std::string s;
  for (size_t i = 0; i < names.size() && i < max_count; ++i) s += (i ? ", " : "") + names[i];
  if (names.size() > max_count) s += ", ... (" + std::to_string(names.size() - max_count) + " more)";
  return s;
}

}  // namespace

namespace {

// Evaluates GT maps gt_dir/names[i] against prediction(i, gt_map) (CV_32F at the GT size, in the
// unit of options.pred_kind); `label(i)` names the prediction in errors. fxb_per_map (when not empty,
// one per name) replaces options' fx * baseline.
DepthEvalResult EvaluateNamedMaps(const std::vector<std::string>& names, const std::string& gt_dir,
                                  const std::function<cv::Mat(size_t, const cv::Mat&)>& prediction,
                                  const std::function<std::string(size_t)>& label, const DepthEvalOptions& options,
                                  const std::vector<double>& fxb_per_map = {}) {
  DepthEvalResult result;
  std::optional<DepthRangeAccumulator> ranges;
  if (!options.range_edges.empty()) ranges.emplace(options.range_edges);
  for (size_t i = 0; i < names.size(); ++i) {
    const std::string& name = names[i];
    const std::string gt_path = JoinPath(gt_dir, name);
    const cv::Mat gt_map = ReadKittiMapPng(gt_path);
    double fxb = fxb_per_map.empty() ? options.fxb : fxb_per_map[i];
    // Only a disparity needs it: depth against depth works at any image width.
    if (fxb_per_map.empty() && options.kitti_focal_by_width && ConvertsDisparity(options)) {
      try {
        fxb = KittiFocalLengthForWidth(gt_map.cols) * kKittiStereoBaseline;
      } catch (const Error& e) {
        throw Error(gt_path, e.what());
      }
    }
    const cv::Mat pred_map = prediction(i, gt_map);
    const cv::Mat gt_depth =
        options.gt_kind == MapKind::kDisparity ? DisparityToDepth(gt_map, fxb, 0.0f) : gt_map;
    const cv::Mat pred_depth = options.pred_kind == MapKind::kDisparity
                                   ? DisparityToDepth(pred_map, fxb, std::numeric_limits<float>::infinity())
                                   : pred_map;
    DepthMetrics metrics;
    try {
      metrics = ComputeDepthMetrics(pred_depth, gt_depth, options);
    } catch (const Error& e) {
      throw Error(label(i), e.what());
    }
    if (metrics.valid_pixels == 0) {
      result.skipped.push_back(name);
      continue;
    }
    result.names.push_back(name);
    result.per_image.push_back(metrics);
    if (ranges) {
      cv::Mat mask;
      if (!options.image_dir.empty()) {
        const std::string image_path = JoinPath(options.image_dir, name);
        const cv::Mat grey = cv::imread(image_path, cv::IMREAD_GRAYSCALE);
        RequireFile(!grey.empty(), image_path, "missing or unreadable image (--images: named like the GT maps)");
        RequireFile(grey.size() == gt_map.size(), image_path,
                    "image size differs from its GT map " + gt_path);
        mask = TexturedPixelMask(grey, options.min_image_gradient);
      }
      try {
        ranges->Add(pred_depth, gt_depth, mask, options, metrics.scale);
      } catch (const Error& e) {
        throw Error(label(i), e.what());
      }
    }
  }
  RequireFile(!result.per_image.empty(), gt_dir,
              "no ground-truth map has a valid pixel inside the crop and (min_depth, max_depth)");
  result.mean = AverageDepthMetrics(result.per_image);
  if (ranges) {
    result.ranges = ranges->Ranges();
    result.all_ranges = ranges->Overall();
  }
  return result;
}

}  // namespace

DepthEvalResult EvaluateDepthFolders(const std::string& pred_dir, const std::string& gt_dir,
                                     const DepthEvalOptions& options) {
  options.Check();
  Require(options.raw_root.empty(), "eval-depth: a KITTI raw root gives fx * baseline per split line: it needs --split");
  const std::vector<std::string> gt_names = ListPngNames(gt_dir);
  const std::vector<std::string> pred_names = ListPngNames(pred_dir);
  std::vector<std::string> only_gt, only_pred;
  std::set_difference(gt_names.begin(), gt_names.end(), pred_names.begin(), pred_names.end(),
                      std::back_inserter(only_gt));
  std::set_difference(pred_names.begin(), pred_names.end(), gt_names.begin(), gt_names.end(),
                      std::back_inserter(only_pred));
  if (!only_gt.empty() || !only_pred.empty()) {
    std::string message = "file names of predictions and ground truth differ:";
    if (!only_gt.empty()) message += " missing in " + pred_dir + ": " + JoinFirst(only_gt, 8) + ";";
    if (!only_pred.empty()) message += " missing in " + gt_dir + ": " + JoinFirst(only_pred, 8) + ";";
    throw Error(message);
  }
  return EvaluateNamedMaps(
      gt_names, gt_dir,
      [&](size_t i, const cv::Mat& gt) {
        return ResizePrediction(ReadKittiMapPng(JoinPath(pred_dir, gt_names[i])), options.pred_kind, gt.size());
      },
      [&](size_t i) { return JoinPath(pred_dir, gt_names[i]); }, options);
}

double SplitLineFxB(const RawCameraCalibration& calibration, int camera) {
  Require(camera == 2 || camera == 3, "split lines evaluate camera 2 or 3, not " + std::to_string(camera));
  const auto centre_x = [&](int c) {
    const Eigen::Matrix<double, 3, 4> p = calibration.Projection(c);
    return -p(0, 3) / p(0, 0);
  };
  const double baseline = centre_x(3) - centre_x(2);
  RequireFile(baseline > 0, calibration.path, "P_rect_02 / P_rect_03 give a non-positive colour baseline");
  return calibration.Projection(camera)(0, 0) * baseline;
}

DepthEvalResult EvaluateDepthSplit(const std::string& split_path, const std::string& pred,
                                   const std::string& gt_dir, const DepthEvalOptions& options) {
  options.Check();
  Require(options.image_dir.empty(), "eval-depth --split: --images is for folder evaluation only");
  const std::vector<SplitEntry> entries = ReadSplitFile(split_path);
  std::vector<std::string> names;
  for (size_t i = 0; i < entries.size(); ++i) {
    names.push_back(SplitMapName(static_cast<int>(i)));
    RequireFile(fs::exists(JoinPath(gt_dir, names.back())), JoinPath(gt_dir, names.back()),
                "no GT map for split line " + std::to_string(i + 1) + " (write them with `dvso gt-depth --split`)");
  }
  std::vector<double> fxb_per_line;  // empty: options' fx * baseline
  if (!options.raw_root.empty() && ConvertsDisparity(options)) {
    std::map<std::string, RawCameraCalibration> calibrations;  // one per calibration folder (raw day)
    for (size_t i = 0; i < entries.size(); ++i) {
      try {
        const std::string dir = FindRawCalibrationDir(JoinPath(options.raw_root, entries[i].drive));
        auto it = calibrations.find(dir);
        if (it == calibrations.end()) it = calibrations.emplace(dir, RawCameraCalibration(dir)).first;
        fxb_per_line.push_back(SplitLineFxB(it->second, entries[i].Camera()));
      } catch (const Error& e) {
        throw Error(split_path, "entry " + std::to_string(i + 1) + " (" + entries[i].drive + "): " + e.what());
      }
    }
  }
  if (fs::path(pred).extension() == ".npy") {
    RequireFile(options.pred_kind == MapKind::kDisparity, pred, "an .npy stack holds disparities / width");
    const NpyDisparityStack stack(pred);
    RequireFile(stack.size() == static_cast<int>(entries.size()), pred,
                std::to_string(stack.size()) + " maps for " + std::to_string(entries.size()) + " split entries");
    return EvaluateNamedMaps(
        names, gt_dir,
        [&](size_t i, const cv::Mat& gt) {
          // A NaN made 0 would be scored as the farthest depth (max_depth): a broken prediction is an error.
          return stack.Frame(static_cast<int>(i), gt.cols, gt.rows, NonFiniteDisparity::kError);
        },
        [&](size_t i) { return pred + " [" + std::to_string(i) + "]"; }, options, fxb_per_line);
  }
  for (const std::string& name : names) {
    RequireFile(fs::exists(JoinPath(pred, name)), JoinPath(pred, name), "no prediction for this split entry");
  }
  return EvaluateNamedMaps(
      names, gt_dir,
      [&](size_t i, const cv::Mat& gt) {
        return ResizePrediction(ReadKittiMapPng(JoinPath(pred, names[i])), options.pred_kind, gt.size());
      },
      [&](size_t i) { return JoinPath(pred, names[i]); }, options, fxb_per_line);
}

namespace {

nlohmann::json MetricsToJson(const DepthMetrics& m, bool with_scale) {
  nlohmann::json j = {{"abs_rel", m.abs_rel}, {"sq_rel", m.sq_rel}, {"rmse", m.rmse},
                      {"rmse_log", m.rmse_log}, {"a1", m.a1},        {"a2", m.a2},
                      {"a3", m.a3},           {"valid_pixels", m.valid_pixels}};
  if (with_scale) j["scale"] = m.scale;
  return j;
}

nlohmann::json RangeToJson(const DepthRangeStats& r) {
  return {{"min_depth", r.min_depth}, {"max_depth", r.max_depth}, {"pixels", r.pixels},
          {"abs_rel", r.abs_rel},     {"a1", r.a1},               {"median_pred_over_gt", r.median_pred_over_gt}};
}

}  // namespace

nlohmann::json DepthEvalResultToJson(const DepthEvalResult& result, const DepthEvalOptions& options) {
  nlohmann::json j = MetricsToJson(result.mean, options.median_scaling);
  j["images"] = result.per_image.size();
  j["skipped_images"] = result.skipped;
  j["crop"] = DepthCropName(options.crop);
  j["min_depth"] = options.min_depth;
  j["max_depth"] = options.max_depth;
  j["median_scaling"] = options.median_scaling;
  j["pred_kind"] = MapKindName(options.pred_kind);
  j["gt_kind"] = MapKindName(options.gt_kind);
  if (ConvertsDisparity(options)) {  // depth against depth uses no fx * baseline: none is reported
    if (options.fxb > 0.0) j["fxb"] = options.fxb;
    if (options.kitti_focal_by_width) j["fxb"] = "KITTI focal length by width x 0.54 m";
    if (!options.raw_root.empty()) {
      j["fxb"] = "per split line: P_rect_0X[0][0] x (b3 - b2) of its drive's calibration";
    }
  }
  nlohmann::json per_image = nlohmann::json::array();
  for (size_t i = 0; i < result.names.size(); ++i) {
    nlohmann::json entry = MetricsToJson(result.per_image[i], options.median_scaling);
    entry["name"] = result.names[i];
    per_image.push_back(entry);
  }
  j["per_image"] = per_image;
  if (!result.ranges.empty()) {
    nlohmann::json ranges = nlohmann::json::array();
    for (const DepthRangeStats& r : result.ranges) ranges.push_back(RangeToJson(r));
    j["ranges"] = {{"min_image_gradient", options.min_image_gradient},
                   {"per_range", ranges},
                   {"all", RangeToJson(result.all_ranges)}};
  }
  return j;
}

std::string FormatDepthEvalResult(const DepthEvalResult& result, const DepthEvalOptions& options) {
  std::ostringstream out;
  out << result.per_image.size() << " images (crop " << DepthCropName(options.crop) << ", depth range ("
      << options.min_depth << ", " << options.max_depth << ") m"
      << (options.median_scaling ? ", median scaling" : "") << ")\n";
  if (!result.skipped.empty()) {
    out << result.skipped.size() << " images without valid GT pixels skipped: " << JoinFirst(result.skipped, 8)
        << "\n";
  }
  const DepthMetrics& m = result.mean;
  out << std::setw(10) << "abs_rel" << std::setw(10) << "sq_rel" << std::setw(10) << "rmse" << std::setw(10)
      << "rmse_log" << std::setw(10) << "a1" << std::setw(10) << "a2" << std::setw(10) << "a3" << "\n";
  out << std::fixed << std::setprecision(4) << std::setw(10) << m.abs_rel << std::setw(10) << m.sq_rel
      << std::setw(10) << m.rmse << std::setw(10) << m.rmse_log << std::setw(10) << m.a1 << std::setw(10) << m.a2
      << std::setw(10) << m.a3 << "\n";
  if (options.median_scaling) out << "mean median-scaling factor: " << m.scale << "\n";
  if (!result.ranges.empty()) {
    out << "\nby GT depth range (pixels pooled over images"
        << (options.image_dir.empty() ? ""
                                      : ", image gradient >= " + FormatNumber(options.min_image_gradient))
        << "; pred/GT < 1: predicted too near)\n";
    out << std::setw(14) << "range m" << std::setw(12) << "pixels" << std::setw(10) << "abs_rel" << std::setw(10)
        << "a1" << std::setw(16) << "median pred/GT" << "\n";
    auto row = [&out](const std::string& name, const DepthRangeStats& r) {
      out << std::setw(14) << name << std::setw(12) << r.pixels << std::setw(10) << r.abs_rel << std::setw(10)
          << r.a1 << std::setw(16) << r.median_pred_over_gt << "\n";
    };
    for (const DepthRangeStats& r : result.ranges) {
      row(FormatNumber(r.min_depth) + "-" + FormatNumber(r.max_depth), r);
    }
    row("all", result.all_ranges);
  }
  return out.str();
}

}  // namespace dvso
