#include "sdso_labels/label_stats.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"

namespace dvso::labels {

void LabelStatistics::AddFrame(const cv::Mat& labels, const cv::Mat& ground_truth) {
  Require(labels.type() == CV_32FC1, "label statistics need CV_32F label maps");
  const bool compare = !ground_truth.empty();
  if (compare) {
    Require(ground_truth.type() == CV_32FC1 && ground_truth.size() == labels.size(),
            "ground-truth disparity must be CV_32F of the label map's size");
  }
  long count = 0;
  for (int y = 0; y < labels.rows; ++y) {
    const float* l = labels.ptr<float>(y);
    const float* g = compare ? ground_truth.ptr<float>(y) : nullptr;
    for (int x = 0; x < labels.cols; ++x) {
      if (!(l[x] > 0.f)) continue;
      ++count;
      if (!compare || !(g[x] > 0.f)) continue;
      const double error = std::abs(static_cast<double>(l[x]) - g[x]);
      ++compared_;
      abs_error_sum_ += error;
      if (error < 1.0) ++within_1px_;
      if (error < 0.03 * g[x]) ++within_3pct_;
    }
  }
  min_labels_ = frames_ == 0 ? count : std::min(min_labels_, count);
  total_labels_ += count;
  ++frames_;
}

void LabelStatistics::Merge(const LabelStatistics& other) {
  if (other.frames_ == 0) return;
  min_labels_ = frames_ == 0 ? other.min_labels_ : std::min(min_labels_, other.min_labels_);
  frames_ += other.frames_;
  total_labels_ += other.total_labels_;
  compared_ += other.compared_;
  within_1px_ += other.within_1px_;
  within_3pct_ += other.within_3pct_;
  abs_error_sum_ += other.abs_error_sum_;
}

nlohmann::json LabelStatistics::ToJson() const {
  nlohmann::json j;
  j["frames"] = frames_;
  j["labels_per_frame_mean"] = mean_labels_per_frame();
  j["labels_per_frame_min"] = min_labels_per_frame();
  if (compared_ > 0) {
    j["compared_labels"] = compared_;
    j["share_within_1px"] = share_within_1px();
    j["share_within_3_percent"] = share_within_3_percent();
    j["mean_abs_error_px"] = mean_absolute_error();
  }
  return j;
}

std::string LabelStatistics::ToText() const {
  std::ostringstream out;
  out.precision(4);
  out << "frames:                 " << frames_ << "\n"
      << "labels per frame:       mean " << mean_labels_per_frame() << ", min " << min_labels_per_frame() << "\n";
  if (compared_ > 0) {
    out << "labels vs ground truth: " << compared_ << " compared\n"
        << "  within 1 px:          " << 100.0 * share_within_1px() << " %\n"
        << "  within 3 %:           " << 100.0 * share_within_3_percent() << " %\n"
        << "  mean abs error:       " << mean_absolute_error() << " px\n";
  }
  return out.str();
}

}  // namespace dvso::labels
