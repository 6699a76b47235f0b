// Stereo verification of label candidates on the labelled frame's own
// rectified pair: a classical matching-confidence test (ZNCC over a square
// window along the scanline, full disparity range). A label survives when the
// best match lies within `max_offset` px of it and is unique — clearly better
// than every match farther than `exclusion` px away. This removes the points
// that Stereo DSO got confidently wrong: periodic texture (bricks, paving),
// edges parallel to the scanline, and projections across occlusions; the
// left-right check (the matched right pixel must match back) removes labels
// on depth edges, where window matching prefers the foreground.
#pragma once

#include <opencv2/core.hpp>

namespace dvso::labels {

struct StereoCheckOptions {
  bool enabled = true;          // apply the check (off: keep every projected label)
  int window_radius = 3;        // half size of the ZNCC window (7x7)
  double max_offset = 0.5;      // px: best match must lie this close to the label
  double exclusion = 2.0;       // px: matches closer than this to the best are not competitors
  double min_cost_gap = 0.02;   // 1-ZNCC of the best competitor minus that of the best match
  double max_cost = 0.7;        // 1-ZNCC of the best match (0 = identical up to gain/offset)
  int max_disparity = 256;      // px: disparities searched are 0..max_disparity (labels stop at 255)
  bool left_right_check = true; // the right pixel's own best match must lead back (occlusions, edges)

  void Check() const;
};

// Filters `labels` (CV_32F disparities, 0 = none) in place using the grey
// rectified pair (CV_8UC1, same size). Returns the number of labels kept.
int VerifyLabelsWithStereo(const cv::Mat& left, const cv::Mat& right, const StereoCheckOptions& options,
                           cv::Mat* labels);

}  // namespace dvso::labels
