// Stereo label check on synthetic rectified pairs: correct labels on unique
// texture survive, wrong ones and ambiguous (periodic) ones do not, and the
// fast checker (box-filtered window statistics, row correlation) decides
// exactly like the straightforward reference.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>
#include <utility>

#include "core/error.h"
#include "sdso_labels/stereo_check.h"

using namespace dvso;
using namespace dvso::labels;

namespace {

// Smooth random texture (unique everywhere at window scale).
cv::Mat RandomTexture(int rows, int cols, unsigned seed) {
  cv::Mat noise(rows, cols, CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::UNIFORM, 0, 255);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 1.0);
  cv::normalize(noise, noise, 20, 235, cv::NORM_MINMAX);
  cv::Mat out;
  noise.convertTo(out, CV_8U);
  return out;
}

// Right image of a fronto-parallel plane at constant disparity: right(x) = left(x + d).
cv::Mat ShiftedRight(const cv::Mat& left, int disparity) {
  cv::Mat right(left.size(), CV_8U, cv::Scalar(128));
  left.colRange(disparity, left.cols).copyTo(right.colRange(0, left.cols - disparity));
  return right;
}

// A foreground square at disparity 20 over a background at disparity 8: the
// square covers left columns [80, 110) and right columns [60, 90), rows [10, 50).
std::pair<cv::Mat, cv::Mat> SquareOverBackground() {
  const cv::Mat background = RandomTexture(60, 200, 2);
  const cv::Mat foreground = RandomTexture(60, 200, 3);
  cv::Mat left = background.clone();
  cv::Mat right = ShiftedRight(background, 8);
  foreground(cv::Rect(80, 10, 30, 40)).copyTo(left(cv::Rect(80, 10, 30, 40)));
  foreground(cv::Rect(80, 10, 30, 40)).copyTo(right(cv::Rect(60, 10, 30, 40)));
  return {left, right};
}

cv::Mat SingleLabel(const cv::Size& size, int x, int y, float disparity) {
  cv::Mat labels(size, CV_32F, cv::Scalar(0));
  labels.at<float>(y, x) = disparity;
  return labels;
}

}  // namespace

TEST(StereoCheck, KeepsCorrectAndRejectsWrongLabels) {
  const cv::Mat left = RandomTexture(60, 160, 1);
  const cv::Mat right = ShiftedRight(left, 12);
  StereoCheckOptions options;
  StereoLabelChecker checker(left, right, options);
  EXPECT_TRUE(checker.Keep(100, 30, 12.0f));
  EXPECT_TRUE(checker.Keep(100, 30, 12.3f));   // within max_offset of the match
  EXPECT_FALSE(checker.Keep(100, 30, 13.0f));  // 1 px off
  EXPECT_FALSE(checker.Keep(100, 30, 30.0f));
  EXPECT_FALSE(checker.Keep(1, 30, 12.0f));    // window leaves the image
  EXPECT_FALSE(checker.Keep(8, 30, 12.0f));    // match would lie left of the right image
  cv::Mat labels = SingleLabel(left.size(), 100, 30, 12.0f);
  EXPECT_EQ(VerifyLabelsWithStereo(left, right, options, &labels), 1);
  labels = SingleLabel(left.size(), 100, 30, 14.0f);
  EXPECT_EQ(VerifyLabelsWithStereo(left, right, options, &labels), 0);
  EXPECT_EQ(labels.at<float>(30, 100), 0.f);
}

TEST(StereoCheck, BestDisparityIsTheMatchKeepCompares) {
  const cv::Mat left = RandomTexture(60, 160, 1);
  const cv::Mat right = ShiftedRight(left, 12);
  StereoLabelChecker checker(left, right, StereoCheckOptions{});
  EXPECT_NEAR(checker.BestDisparity(100, 30), 12.0, 0.1);  // parabola fit of the cost: a few 0.01 px of bias
  EXPECT_TRUE(checker.Keep(100, 30, static_cast<float>(checker.BestDisparity(100, 30))));
  EXPECT_EQ(checker.BestDisparity(1, 30), -1.0);    // window leaves the image
  EXPECT_EQ(checker.BestDisparity(100, 58), -1.0);
  const cv::Mat flat(60, 160, CV_8U, cv::Scalar(90));
  StereoLabelChecker flat_checker(flat, flat, StereoCheckOptions{});
  EXPECT_EQ(flat_checker.BestDisparity(100, 30), -1.0);  // no texture, no match
}

TEST(StereoCheck, RightImageLabelsMatchIntoTheLeftImage) {
  const cv::Mat left = RandomTexture(60, 160, 6);
  const cv::Mat right = ShiftedRight(left, 12);  // right x shows left x + 12
  StereoCheckOptions options;
  cv::Mat labels = SingleLabel(left.size(), 60, 30, 12.0f);
  EXPECT_EQ(VerifyRightLabelsWithStereo(left, right, options, &labels), 1);
  EXPECT_FLOAT_EQ(labels.at<float>(30, 60), 12.0f);  // mirrored back in place
  labels = SingleLabel(left.size(), 60, 30, 13.5f);
  EXPECT_EQ(VerifyRightLabelsWithStereo(left, right, options, &labels), 0);
  // The left-image test on the same label fails: it would look 12 px to the left.
  labels = SingleLabel(left.size(), 60, 30, 12.0f);
  cv::Mat right_as_left = right.clone();
  EXPECT_EQ(VerifyLabelsWithStereo(right_as_left, left, options, &labels), 0);
}

TEST(StereoCheck, RejectsPeriodicTextureAndTexturelessWindows) {
  // Vertical stripes with an 8 px period: the match at the right disparity is
  // exact, but so are the ones 8 px away -> not unique.
  cv::Mat left(40, 160, CV_8U);
  for (int y = 0; y < left.rows; ++y) {
    for (int x = 0; x < left.cols; ++x) left.at<uchar>(y, x) = static_cast<uchar>(128 + 80 * std::sin(x * CV_PI / 4));
  }
  const cv::Mat right = ShiftedRight(left, 10);
  StereoLabelChecker checker(left, right, StereoCheckOptions());
  EXPECT_FALSE(checker.Keep(100, 20, 10.0f));
  EXPECT_FALSE(checker.Keep(100, 20, 18.0f));  // an equally good alias
  // Without the uniqueness gap an exact match is accepted.
  StereoCheckOptions no_uniqueness;
  no_uniqueness.min_cost_gap = 0;
  no_uniqueness.left_right_check = false;
  no_uniqueness.max_offset = no_uniqueness.exclusion = 20;
  StereoLabelChecker lenient(left, right, no_uniqueness);
  EXPECT_TRUE(lenient.Keep(100, 20, 10.0f));

  const cv::Mat flat(40, 160, CV_8U, cv::Scalar(90));
  StereoLabelChecker flat_checker(flat, flat, StereoCheckOptions());
  EXPECT_FALSE(flat_checker.Keep(100, 20, 5.0f));
}

TEST(StereoCheck, RejectsOccludedBackgroundKeepsVisibleSurfaces) {
  // Background at disparity 8, a foreground square at disparity 20 covering
  // right-image columns [60, 90) (left columns [80, 110)). Left pixels just
  // left of the square see background that is hidden in the right image.
  const auto [left, right] = SquareOverBackground();
  StereoCheckOptions options;
  StereoLabelChecker checker(left, right, options);
  EXPECT_TRUE(checker.Keep(95, 30, 20.0f));  // foreground
  EXPECT_TRUE(checker.Keep(40, 30, 8.0f));   // visible background
  // Left x = 74: its background match x = 66 lies under the foreground in the right image.
  EXPECT_FALSE(checker.Keep(74, 30, 8.0f));
}

TEST(StereoCheck, ShiftedWindowsRejectLabelsAtDepthEdges) {
  const auto [left, right] = SquareOverBackground();
  StereoCheckOptions centred;
  centred.edge_shift = 0;
  centred.left_right_check = false;
  StereoCheckOptions shifted = centred;
  shifted.edge_shift = 3;
  shifted.edge_max_cost = 0.4;
  StereoLabelChecker plain(left, right, centred), edge_aware(left, right, shifted);
  // On the silhouette's first columns the centred window still matches (mostly foreground) ...
  EXPECT_TRUE(plain.Keep(80, 30, 20.0f));
  EXPECT_TRUE(plain.Keep(81, 30, 20.0f));
  // ... but the window shifted onto the background does not.
  EXPECT_FALSE(edge_aware.Keep(80, 30, 20.0f));
  EXPECT_FALSE(edge_aware.Keep(81, 30, 20.0f));
  // Away from edges every shifted window lies on the same surface.
  EXPECT_TRUE(edge_aware.Keep(95, 30, 20.0f));
  EXPECT_TRUE(edge_aware.Keep(40, 30, 8.0f));
}

TEST(StereoCheck, FastCheckerAgreesWithReference) {
  const cv::Mat left = RandomTexture(80, 240, 4);
  // A slanted surface: disparity grows with the row (10 .. 25 px), plus random labels.
  cv::Mat right(left.size(), CV_8U);
  for (int y = 0; y < left.rows; ++y) {
    const int d = 10 + (15 * y) / left.rows;
    for (int x = 0; x < left.cols; ++x) right.at<uchar>(y, x) = left.at<uchar>(y, std::min(left.cols - 1, x + d));
  }
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> any_disparity(0.5f, 60.f);
  cv::Mat labels(left.size(), CV_32F, cv::Scalar(0));
  for (int y = 0; y < left.rows; y += 2) {
    for (int x = 0; x < left.cols; x += 3) {
      const bool correct = (x + y) % 2 == 0;
      labels.at<float>(y, x) = correct ? 10 + (15 * y) / left.rows : any_disparity(rng);
    }
  }
  StereoCheckOptions options;
  cv::Mat fast = labels.clone(), reference = labels.clone();
  const int kept_fast = VerifyLabelsWithStereo(left, right, options, &fast);
  const int kept_reference = VerifyLabelsWithStereoReference(left, right, options, &reference);
  EXPECT_GT(kept_reference, 300);  // the correct labels away from the borders survive
  EXPECT_LT(kept_reference, cv::countNonZero(labels) * 3 / 4);
  // Float rounding may flip a decision exactly at a threshold, nothing more.
  EXPECT_NEAR(kept_fast, kept_reference, 2);
  EXPECT_LE(cv::countNonZero(fast != reference), 2);
}

TEST(StereoCheck, OptionsAreChecked) {
  StereoCheckOptions bad;
  bad.max_offset = 3;
  bad.exclusion = 2;
  EXPECT_THROW(bad.Check(), Error);
  StereoCheckOptions bad_gap;
  bad_gap.edge_distinct_gap = -0.1;
  EXPECT_THROW(bad_gap.Check(), Error);
  const cv::Mat left(20, 40, CV_8U, cv::Scalar(0));
  const cv::Mat colour(20, 40, CV_8UC3);
  EXPECT_THROW(StereoLabelChecker(left, colour, StereoCheckOptions()), Error);
}

TEST(StereoCheck, DistinctShiftedWindowsKeepRightLabelsBesideSilhouettes) {
  // SquareOverBackground: foreground rows [10, 50), left columns [80, 110), disparity 20, over
  // a background at disparity 8. Near the square a shifted window covers both surfaces and
  // exceeds edge_max_cost even at a right label; edge_distinct_gap keeps it when that window
  // still matches the label clearly better than 2-4 px away.
  const auto [left, right] = SquareOverBackground();
  StereoCheckOptions plain;
  plain.edge_shift = 3;
  plain.edge_max_cost = 0.4;
  plain.left_right_check = false;
  plain.min_cost_gap = 0;
  plain.max_offset = 0.75;
  StereoCheckOptions distinct = plain;
  distinct.edge_distinct_gap = 0.1;
  StereoCheckOptions centred_only = plain;
  centred_only.edge_shift = 0;
  StereoLabelChecker old_rule(left, right, plain), new_rule(left, right, distinct),
      no_edge_test(left, right, centred_only);
  struct Label {
    int x, y;
    float disparity;
  };
  // Right labels two rows inside the square's top edge and on the background just above and
  // below it: the plain test drops them, the distinct one keeps them.
  for (const Label& l : {Label{86, 12, 20.f}, Label{80, 9, 8.f}, Label{79, 8, 8.f}, Label{77, 50, 8.f}}) {
    EXPECT_FALSE(old_rule.Keep(l.x, l.y, l.disparity)) << l.x << "," << l.y;
    EXPECT_TRUE(new_rule.Keep(l.x, l.y, l.disparity)) << l.x << "," << l.y;
  }
  // Background pixels beside the square's sides labelled with the foreground's disparity (the
  // silhouette error): the centred window still matches there, but the window on their own
  // side sees only background, which matches 20 no better than 16-24, so both rules drop them.
  for (const Label& l : {Label{79, 30, 20.f}, Label{110, 20, 20.f}, Label{111, 30, 20.f}, Label{110, 40, 20.f}}) {
    EXPECT_TRUE(no_edge_test.Keep(l.x, l.y, l.disparity)) << l.x << "," << l.y;
    EXPECT_FALSE(old_rule.Keep(l.x, l.y, l.disparity)) << l.x << "," << l.y;
    EXPECT_FALSE(new_rule.Keep(l.x, l.y, l.disparity)) << l.x << "," << l.y;
  }
  // Inside the surfaces nothing changes.
  EXPECT_TRUE(new_rule.Keep(95, 30, 20.0f));
  EXPECT_TRUE(new_rule.Keep(40, 30, 8.0f));
}
