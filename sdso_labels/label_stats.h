// Label quality and coverage statistics for `dvso labels` summaries.
#pragma once

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <string>

namespace dvso::labels {

// Accumulates per-frame label counts and, when ground truth is given, the
// accuracy of the labels against it.
class LabelStatistics {
 public:
  // `labels` and `ground_truth` are CV_32F disparity maps, 0 = none/unknown;
  // ground_truth may be empty (no accuracy then).
  void AddFrame(const cv::Mat& labels, const cv::Mat& ground_truth = cv::Mat());
  // Adds every frame of `other` (the statistics of several sequences together).
  void Merge(const LabelStatistics& other);

  long frames() const { return frames_; }
  double mean_labels_per_frame() const { return frames_ ? static_cast<double>(total_labels_) / frames_ : 0.0; }
  long min_labels_per_frame() const { return frames_ ? min_labels_ : 0; }
  long compared() const { return compared_; }
  // Shares of compared labels with |error| < 1 px and |error| < 3 % of the truth.
  double share_within_1px() const { return compared_ ? static_cast<double>(within_1px_) / compared_ : 0.0; }
  double share_within_3_percent() const { return compared_ ? static_cast<double>(within_3pct_) / compared_ : 0.0; }
  double mean_absolute_error() const { return compared_ ? abs_error_sum_ / compared_ : 0.0; }

  nlohmann::json ToJson() const;
  std::string ToText() const;

 private:
  long frames_ = 0, total_labels_ = 0, min_labels_ = 0;
  long compared_ = 0, within_1px_ = 0, within_3pct_ = 0;
  double abs_error_sum_ = 0.0;
};

}  // namespace dvso::labels
