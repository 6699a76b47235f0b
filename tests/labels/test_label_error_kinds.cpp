// Label places by kind (sdso_labels/label_error_kinds.h) on constructed GT maps
// whose kind at each pixel is known by construction.
#include <gtest/gtest.h>

#include "core/error.h"
#include "sdso_labels/label_error_kinds.h"

namespace dvso::labels {
namespace {

constexpr int kWidth = 100, kHeight = 20;
constexpr float kBackground = 10.f;  // px, not far: far_fraction 0.008 * 100 = 0.8 px

// Background at 10 px; a 3 px wide pole at 20 px (columns 30-32); a wide
// foreground wall at 20 px from column 60 on; far sky-like band (0.5 px) in
// columns 85.. of rows 0-4.
cv::Mat ConstructedGroundTruth() {
  cv::Mat gt(kHeight, kWidth, CV_32F, cv::Scalar(kBackground));
  gt.colRange(30, 33).setTo(20.f);
  gt.colRange(60, kWidth).setTo(20.f);
  gt(cv::Rect(85, 0, 15, 5)).setTo(0.5f);
  return gt;
}

// Textured (checkerboard of 0 / 60) except a flat patch in columns 40-49.
cv::Mat ConstructedImage() {
  cv::Mat image(kHeight, kWidth, CV_8U);
  for (int y = 0; y < kHeight; ++y)
    for (int x = 0; x < kWidth; ++x) image.at<uint8_t>(y, x) = ((x + y) % 2) ? 60 : 0;
  image.colRange(38, 52).setTo(128);
  return image;
}

TEST(LabelErrorKinds, ClassifiesConstructedPlaces) {
  const cv::Mat gt = ConstructedGroundTruth(), image = ConstructedImage();
  const LabelErrorKindOptions o;
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 31, 10, o), LabelSceneKind::kThin);       // pole centre
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 30, 10, o), LabelSceneKind::kThin);       // pole border
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 60, 10, o), LabelSceneKind::kDepthEdge);  // wall silhouette
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 58, 10, o), LabelSceneKind::kDepthEdge);  // background beside it
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 28, 10, o), LabelSceneKind::kDepthEdge);  // background 2 px from pole
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 95, 1, o), LabelSceneKind::kFar);
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 45, 10, o), LabelSceneKind::kLowTexture);
  EXPECT_EQ(ClassifyLabelPlace(gt, cv::Mat(), 45, 10, o), LabelSceneKind::kOther);  // no image: no texture test
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 15, 10, o), LabelSceneKind::kOther);
  EXPECT_EQ(ClassifyLabelPlace(gt, image, 70, 10, o), LabelSceneKind::kOther);      // inside the wide wall
}

TEST(LabelErrorKinds, UnknownGroundTruthIsNeverABackground) {
  cv::Mat gt(5, 20, CV_32F, cv::Scalar(0.f));
  gt.colRange(8, 11).setTo(20.f);  // a 3 px structure with no GT on either side (e.g. sky)
  const LabelErrorKindOptions o;
  EXPECT_EQ(ClassifyLabelPlace(gt, cv::Mat(), 9, 2, o), LabelSceneKind::kOther);
}

TEST(LabelErrorKinds, BreakdownCountsLabelsAndWrongLabelsPerKind) {
  const cv::Mat gt = ConstructedGroundTruth(), image = ConstructedImage();
  cv::Mat labels(kHeight, kWidth, CV_32F, cv::Scalar(0.f));
  labels.at<float>(10, 31) = 15.f;   // thin, wrong by 5 px (took the background-ish depth)
  labels.at<float>(11, 31) = 20.4f;  // thin, right
  labels.at<float>(10, 60) = 10.f;   // depth edge, wrong by 10 px
  labels.at<float>(10, 15) = 10.5f;  // other, right
  labels.at<float>(10, 16) = 11.5f;  // other, wrong by 1.5 px
  labels.at<float>(10, 45) = 10.9f;  // low texture, right (0.9 px)
  LabelErrorBreakdown breakdown;
  breakdown.AddFrame(labels, gt, image);
  EXPECT_EQ(breakdown.total_labels(), 6);
  EXPECT_EQ(breakdown.total_wrong(), 3);
  EXPECT_EQ(breakdown.labels(LabelSceneKind::kThin), 2);
  EXPECT_EQ(breakdown.wrong(LabelSceneKind::kThin), 1);
  EXPECT_EQ(breakdown.wrong(LabelSceneKind::kDepthEdge), 1);
  EXPECT_EQ(breakdown.labels(LabelSceneKind::kOther), 2);
  EXPECT_EQ(breakdown.wrong(LabelSceneKind::kOther), 1);
  EXPECT_EQ(breakdown.labels(LabelSceneKind::kLowTexture), 1);
  EXPECT_EQ(breakdown.wrong(LabelSceneKind::kLowTexture), 0);
  const nlohmann::json j = breakdown.ToJson();
  EXPECT_DOUBLE_EQ(j["thin"]["share_within_threshold"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(j["depth_edge"]["share_of_wrong"].get<double>(), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(j["other"]["share_of_labels"].get<double>(), 2.0 / 6.0);
}

TEST(LabelErrorKinds, RejectsBadOptionsAndMismatchedMaps) {
  LabelErrorKindOptions bad;
  bad.edge_margin = 0;
  EXPECT_ANY_THROW(LabelErrorBreakdown{bad});
  LabelErrorBreakdown breakdown;
  EXPECT_ANY_THROW(breakdown.AddFrame(cv::Mat(4, 4, CV_32F, 0.f), cv::Mat(4, 5, CV_32F, 0.f)));
}

}  // namespace
}  // namespace dvso::labels

TEST(LabelErrorKinds, PictureShowsRightLabelsGreenAndWrongOnesRed) {
  cv::Mat gt(20, 40, CV_32F, cv::Scalar(10.f)), labels(20, 40, CV_32F, cv::Scalar(0.f));
  gt.at<float>(15, 35) = 0.f;       // no GT there
  labels.at<float>(5, 5) = 10.5f;   // right (0.5 px off)
  labels.at<float>(10, 20) = 12.f;  // wrong (2 px off)
  labels.at<float>(15, 35) = 7.f;   // no GT to compare with
  const cv::Mat image(20, 40, CV_8UC1, cv::Scalar(100));
  const cv::Mat picture = dvso::labels::RenderLabelErrors(labels, gt, image, 1.0);
  ASSERT_EQ(picture.type(), CV_8UC3);
  EXPECT_EQ(picture.at<cv::Vec3b>(5, 5), cv::Vec3b(0, 200, 0));
  EXPECT_EQ(picture.at<cv::Vec3b>(10, 20), cv::Vec3b(0, 0, 255));
  EXPECT_EQ(picture.at<cv::Vec3b>(10, 22), cv::Vec3b(0, 0, 255));  // wrong labels are drawn larger
  EXPECT_EQ(picture.at<cv::Vec3b>(15, 35), cv::Vec3b(0, 220, 220));
  EXPECT_EQ(picture.at<cv::Vec3b>(0, 39), cv::Vec3b(100, 100, 100));  // the image elsewhere
  // With a 3 px threshold the 2 px label is right.
  EXPECT_EQ(dvso::labels::RenderLabelErrors(labels, gt, image, 3.0).at<cv::Vec3b>(10, 20), cv::Vec3b(0, 200, 0));
  EXPECT_THROW(dvso::labels::RenderLabelErrors(labels, gt, cv::Mat(), 1.0), dvso::Error);
}
