// Stereo verification of label candidates on the labelled frame's own
// rectified pair: a classical matching-confidence test (ZNCC over a square
// window along the scanline, full disparity range). A label survives when the
// best match over the whole range lies within `max_offset` px of it (so
// periodic texture and edges parallel to the scanline, where Stereo DSO finds
// confidently wrong minima, fail unless the label is the global optimum),
// optionally with a cost gap to every match farther than `exclusion` px
// (uniqueness) and a left-right check (the matched right pixel must match
// back: occlusions). Depth edges: window matching "fattens" the foreground,
// so the windows shifted left/right/up/down must match at the label too; at a
// silhouette one of them covers the other surface and fails.
//
// Speed: window means and norms come from box filters computed once per
// frame, so a label's whole disparity scan costs one multiply-add per window
// pixel and disparity, laid out as a contiguous 1-D correlation per window
// row (vectorised by the compiler); a band of disparities around the label
// is tested first, so most wrong labels never need the full scan.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

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
  // Depth-edge test with shifted windows: the windows centred `edge_shift` px left, right,
  // above and below the pixel must also match at the label (cost <= edge_max_cost). At a
  // depth edge one of them covers the other surface and fails, so labels next to
  // silhouettes (where window matching "fattens" the foreground and a one-pixel error
  // swaps foreground and background) are dropped. 0 = off.
  int edge_shift = 0;
  double edge_max_cost = 0.5;
  // A shifted window above `edge_max_cost` (but within `max_cost`) still passes when it
  // prefers the label clearly: its cost there is at least this much below its best cost
  // 2-4 px to either side (kEdgeCompetitorOffsets; disparities whose window leaves the
  // image are not competitors, and a window with none fails). Such a window straddles a
  // silhouette but its texture is the label's surface (a right label beside an edge),
  // whereas a window that only sees the other surface or flat noise matches every
  // disparity alike. 0 = off (session 37, docs/labels.md).
  double edge_distinct_gap = 0.0;

  void Check() const;
};

// Checks labels of one stereo pair. Construction precomputes the window
// statistics of both images (a few ms at KITTI size); Keep() then tests one
// label. Reuse one instance per frame.
class StereoLabelChecker {
 public:
  // Grey rectified pair, CV_8UC1, same size.
  StereoLabelChecker(const cv::Mat& left, const cv::Mat& right, const StereoCheckOptions& options);

  // True when the label `disparity` (px) at left pixel (x, y) passes the test.
  bool Keep(int x, int y, float disparity);

  // Sub-pixel disparity of the best match over the whole range at left pixel
  // (x, y) (the match Keep() compares a label with); -1 when the window does
  // not fit or has no texture.
  double BestDisparity(int x, int y);

 private:
  // 1 - ZNCC of the left window at (x, y) and the right one at x - disparity
  // (linear between the two integer disparities around it).
  float CostAt(int x, int y, float disparity) const;
  // Matching costs (1 - ZNCC) of the window of `fixed` at (x, y) against the
  // windows of `other` centred at x_begin .. x_end - 1 of the same row.
  void ScanCosts(const cv::Mat& fixed, const cv::Mat& fixed_mean, const cv::Mat& fixed_norm, const cv::Mat& other,
                 const cv::Mat& other_norm, int x, int y, int x_begin, int x_end, std::vector<float>* costs);
  // Fills costs_[d] for d = 0 .. max_d at left pixel (x, y); returns the best d.
  int ScanFullRange(int x, int y, int max_d);

  StereoCheckOptions options_;
  cv::Mat left_, right_;            // CV_32F, centred around 0 (keeps float sums accurate)
  cv::Mat left_mean_, right_mean_;  // window means
  cv::Mat left_norm_, right_norm_;  // window norms sqrt(sum (I - mean)^2)
  std::vector<float> cross_, costs_, back_costs_, weights_;
};

// Filters `labels` (CV_32F disparities, 0 = none) in place using the grey
// rectified pair (CV_8UC1, same size). Returns the number of labels kept.
int VerifyLabelsWithStereo(const cv::Mat& left, const cv::Mat& right, const StereoCheckOptions& options,
                           cv::Mat* labels);

// The same test for labels of the RIGHT image (right pixel x matches left
// x + disparity): runs the left-image test on the mirrored pair.
int VerifyRightLabelsWithStereo(const cv::Mat& left, const cv::Mat& right, const StereoCheckOptions& options,
                                cv::Mat* right_labels);

// The same test with the straightforward per-disparity window sums (slow;
// the reference the fast checker is tested against).
int VerifyLabelsWithStereoReference(const cv::Mat& left, const cv::Mat& right, const StereoCheckOptions& options,
                                    cv::Mat* labels);

}  // namespace dvso::labels
