#include "sdso_labels/label_error_kinds.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <opencv2/imgproc.hpp>

#include "core/error.h"

namespace dvso::labels {

const char* LabelSceneKindName(LabelSceneKind kind) {
  switch (kind) {
    case LabelSceneKind::kThin: return "thin";
    case LabelSceneKind::kDepthEdge: return "depth_edge";
    case LabelSceneKind::kFar: return "far";
    case LabelSceneKind::kLowTexture: return "low_texture";
    case LabelSceneKind::kOther: return "other";
  }
  return "?";
}

void LabelErrorKindOptions::Check() const {
  Require(thin_radius >= 1 && thin_radius <= 32, "label kinds: thin radius must be in [1, 32] px");
  Require(edge_radius >= 1 && edge_radius <= 32, "label kinds: edge radius must be in [1, 32] px");
  Require(edge_margin > 0 && edge_margin < 1, "label kinds: edge margin must be in (0, 1)");
  Require(far_fraction >= 0 && far_fraction < 0.5, "label kinds: far fraction must be in [0, 0.5)");
  Require(low_texture_gradient >= 0, "label kinds: low-texture gradient must be >= 0");
  Require(wrong_threshold > 0, "label kinds: wrong threshold must be > 0 px");
}

namespace {

// True when `neighbour` (a GT disparity, 0 = unknown) is farther than `centre`
// by more than the relative margin: a known background next to the point.
bool MarkedlyFarther(float neighbour, float centre, double margin) {
  return neighbour > 0.f && neighbour < centre * (1.0 - margin);
}

// A nearer structure at most 2r+1 px wide: farther GT within r px on both sides.
bool IsThin(const cv::Mat& gt, int x, int y, const LabelErrorKindOptions& o) {
  const float* row = gt.ptr<float>(y);
  const float centre = row[x];
  bool left = false, right = false;
  for (int d = 1; d <= o.thin_radius; ++d) {
    if (x - d >= 0 && MarkedlyFarther(row[x - d], centre, o.edge_margin)) left = true;
    if (x + d < gt.cols && MarkedlyFarther(row[x + d], centre, o.edge_margin)) right = true;
  }
  return left && right;
}

bool IsDepthEdge(const cv::Mat& gt, int x, int y, const LabelErrorKindOptions& o) {
  float lowest = std::numeric_limits<float>::max(), highest = 0.f;
  for (int v = std::max(0, y - o.edge_radius); v <= std::min(gt.rows - 1, y + o.edge_radius); ++v) {
    const float* row = gt.ptr<float>(v);
    for (int u = std::max(0, x - o.edge_radius); u <= std::min(gt.cols - 1, x + o.edge_radius); ++u) {
      if (!(row[u] > 0.f)) continue;
      lowest = std::min(lowest, row[u]);
      highest = std::max(highest, row[u]);
    }
  }
  return highest > 0.f && lowest < highest * (1.0 - o.edge_margin);
}

// Mean |dI/dx| + |dI/dy| (forward differences) over the edge window.
double MeanGradient(const cv::Mat& image, int x, int y, int radius) {
  double sum = 0;
  int n = 0;
  for (int v = std::max(0, y - radius); v <= std::min(image.rows - 2, y + radius); ++v) {
    const uint8_t* row = image.ptr<uint8_t>(v);
    const uint8_t* below = image.ptr<uint8_t>(v + 1);
    for (int u = std::max(0, x - radius); u <= std::min(image.cols - 2, x + radius); ++u) {
      sum += std::abs(row[u + 1] - row[u]) + std::abs(below[u] - row[u]);
      ++n;
    }
  }
  return n > 0 ? sum / n : 0.0;
}

}  // namespace

cv::Mat RenderLabelErrors(const cv::Mat& labels, const cv::Mat& ground_truth, const cv::Mat& image,
                          double wrong_threshold) {
  Require(labels.type() == CV_32F && ground_truth.type() == CV_32F && labels.size() == ground_truth.size(),
          "RenderLabelErrors: labels and GT must be CV_32F maps of one size");
  Require(image.type() == CV_8UC1 && image.size() == labels.size(), "RenderLabelErrors: image must be grey, same size");
  const cv::Scalar kRight(0, 200, 0), kWrong(0, 0, 255), kNoGroundTruth(0, 220, 220);  // BGR
  constexpr int kRightRadius = 1, kWrongRadius = 2;  // wrong labels drawn last and larger: they are the few
  cv::Mat picture;
  cv::cvtColor(image, picture, cv::COLOR_GRAY2BGR);
  std::vector<cv::Point> wrong;
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      const float label = labels.at<float>(y, x);
      if (!(label > 0.f)) continue;
      const float gt = ground_truth.at<float>(y, x);
      if (!(gt > 0.f)) {
        cv::circle(picture, {x, y}, kRightRadius, kNoGroundTruth, cv::FILLED);
      } else if (std::abs(label - gt) > wrong_threshold) {
        wrong.emplace_back(x, y);
      } else {
        cv::circle(picture, {x, y}, kRightRadius, kRight, cv::FILLED);
      }
    }
  }
  for (const cv::Point& p : wrong) cv::circle(picture, p, kWrongRadius, kWrong, cv::FILLED);
  return picture;
}

LabelSceneKind ClassifyLabelPlace(const cv::Mat& ground_truth, const cv::Mat& image, int x, int y,
                                  const LabelErrorKindOptions& options) {
  if (IsThin(ground_truth, x, y, options)) return LabelSceneKind::kThin;
  if (IsDepthEdge(ground_truth, x, y, options)) return LabelSceneKind::kDepthEdge;
  if (ground_truth.at<float>(y, x) < options.far_fraction * ground_truth.cols) return LabelSceneKind::kFar;
  if (!image.empty() && MeanGradient(image, x, y, options.edge_radius) < options.low_texture_gradient)
    return LabelSceneKind::kLowTexture;
  return LabelSceneKind::kOther;
}

LabelErrorBreakdown::LabelErrorBreakdown(LabelErrorKindOptions options) : options_(options) { options_.Check(); }

void LabelErrorBreakdown::AddFrame(const cv::Mat& labels, const cv::Mat& ground_truth, const cv::Mat& image) {
  Require(labels.type() == CV_32FC1 && ground_truth.type() == CV_32FC1 && labels.size() == ground_truth.size(),
          "label breakdown: labels and GT must be CV_32F maps of one size");
  Require(image.empty() || (image.type() == CV_8UC1 && image.size() == labels.size()),
          "label breakdown: the image must be 8-bit grey of the label map's size");
  for (int y = 0; y < labels.rows; ++y) {
    const float* l = labels.ptr<float>(y);
    const float* g = ground_truth.ptr<float>(y);
    for (int x = 0; x < labels.cols; ++x) {
      if (!(l[x] > 0.f) || !(g[x] > 0.f)) continue;
      const int kind = static_cast<int>(ClassifyLabelPlace(ground_truth, image, x, y, options_));
      ++labels_[kind];
      if (std::abs(l[x] - g[x]) > options_.wrong_threshold) ++wrong_[kind];
    }
  }
}

long LabelErrorBreakdown::total_labels() const {
  long n = 0;
  for (long v : labels_) n += v;
  return n;
}

long LabelErrorBreakdown::total_wrong() const {
  long n = 0;
  for (long v : wrong_) n += v;
  return n;
}

nlohmann::json LabelErrorBreakdown::ToJson() const {
  nlohmann::json j;
  for (int k = 0; k < kNumLabelSceneKinds; ++k) {
    const auto kind = static_cast<LabelSceneKind>(k);
    j[LabelSceneKindName(kind)] = {
        {"labels", labels_[k]},
        {"wrong", wrong_[k]},
        {"share_of_labels", total_labels() ? static_cast<double>(labels_[k]) / total_labels() : 0.0},
        {"share_within_threshold", labels_[k] ? 1.0 - static_cast<double>(wrong_[k]) / labels_[k] : 0.0},
        {"share_of_wrong", total_wrong() ? static_cast<double>(wrong_[k]) / total_wrong() : 0.0}};
  }
  return j;
}

std::string LabelErrorBreakdown::ToText() const {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1);
  out << "  kind         labels %   within " << options_.wrong_threshold << " px %   of wrong labels %\n";
  for (int k = 0; k < kNumLabelSceneKinds; ++k) {
    const double share = total_labels() ? 100.0 * labels_[k] / total_labels() : 0.0;
    const double right = labels_[k] ? 100.0 * (1.0 - static_cast<double>(wrong_[k]) / labels_[k]) : 0.0;
    const double of_wrong = total_wrong() ? 100.0 * wrong_[k] / total_wrong() : 0.0;
    out << "  " << std::left << std::setw(12) << LabelSceneKindName(static_cast<LabelSceneKind>(k)) << std::right
        << std::setw(8) << share << std::setw(16) << right << std::setw(20) << of_wrong << "\n";
  }
  return out.str();
}

}  // namespace dvso::labels
