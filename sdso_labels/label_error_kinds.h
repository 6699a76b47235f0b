// Where wrong labels sit (issue 12): every label compared with a GT disparity
// map is put into one scene kind decided from the GT (and the image), so a
// label folder's accuracy can be broken down by the kind of place it labels.
// The kinds are tested in this order; a label belongs to the first that holds:
//   thin        a nearer structure at most 2 * thin_radius + 1 px wide: the GT
//               within thin_radius px on BOTH sides along the row is farther by
//               more than edge_margin (poles, trunks, sign posts);
//   depth_edge  the GT disparities in the (2 * edge_radius + 1)^2 window differ by
//               more than edge_margin relative (silhouettes, occlusion boundaries);
//   far         GT disparity below far_fraction of the image width (width-
//               normalised, so one threshold means one depth at any resolution);
//   low_texture mean absolute image gradient in the window below
//               low_texture_gradient grey levels per px (needs the image);
//   other       none of the above (textured surfaces in the open).
// Periodic texture and moving objects are not separated: the first needs the
// matching cost curve, and the simulator has no moving objects.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>

namespace dvso::labels {

enum class LabelSceneKind { kThin = 0, kDepthEdge, kFar, kLowTexture, kOther };
constexpr int kNumLabelSceneKinds = 5;
const char* LabelSceneKindName(LabelSceneKind kind);

struct LabelErrorKindOptions {
  int thin_radius = 3;                // px: a thin structure is at most 7 px wide
  int edge_radius = 2;                // px: half size of the depth-edge window (5x5)
  double edge_margin = 0.10;          // relative GT disparity difference that counts as a depth change
  double far_fraction = 0.008;        // of the width: 10 px at 1241 (~39 m on KITTI), 5 px at 640
  double low_texture_gradient = 4.0;  // grey levels per px, mean |dI/dx| + |dI/dy| over the window
  double wrong_threshold = 1.0;       // px: a label farther than this from the GT is wrong

  void Check() const;
};

// Kind of the place at (x, y) of `ground_truth` (CV_32F disparity, 0 = unknown);
// `image` (CV_8UC1, same size) may be empty: then low_texture is never chosen.
LabelSceneKind ClassifyLabelPlace(const cv::Mat& ground_truth, const cv::Mat& image, int x, int y,
                                  const LabelErrorKindOptions& options);

// A picture of one frame's labels for people to look at: the grey `image` (CV_8UC1)
// in colour with every label that has a GT value drawn as a dot, green when within
// `wrong_threshold` px of the GT, red (larger) when wrong; labels without GT in yellow.
cv::Mat RenderLabelErrors(const cv::Mat& labels, const cv::Mat& ground_truth, const cv::Mat& image,
                          double wrong_threshold);

// Counts labels and wrong labels per kind over frames.
class LabelErrorBreakdown {
 public:
  explicit LabelErrorBreakdown(LabelErrorKindOptions options = {});

  // `labels` and `ground_truth`: CV_32F disparity maps of one size, 0 = none;
  // `image`: CV_8UC1 grey of that size or empty.
  void AddFrame(const cv::Mat& labels, const cv::Mat& ground_truth, const cv::Mat& image = cv::Mat());

  long labels(LabelSceneKind kind) const { return labels_[static_cast<int>(kind)]; }
  long wrong(LabelSceneKind kind) const { return wrong_[static_cast<int>(kind)]; }
  long total_labels() const;
  long total_wrong() const;

  nlohmann::json ToJson() const;
  // A table: kind | share of labels | share within 1 px | share of all wrong labels.
  std::string ToText() const;

 private:
  LabelErrorKindOptions options_;
  std::array<long, kNumLabelSceneKinds> labels_{}, wrong_{};
};

}  // namespace dvso::labels
