// Label rendering and statistics against hand-computed cases.
#include <gtest/gtest.h>

#include "core/error.h"
#include "sdso_labels/label_map.h"
#include "sdso_labels/label_stats.h"

using namespace dvso;
using namespace dvso::labels;

namespace {
StereoCamera SmallCamera() {
  StereoCamera c;
  c.left = PinholeCamera{100, 100, 20, 10, 41, 21};
  c.baseline = 0.5;
  return c;
}
}  // namespace

TEST(LabelMap, ProjectsDisparityFxBOverZ) {
  const StereoCamera cam = SmallCamera();
  std::vector<LabelPoint> points = {{Eigen::Vector3d(0, 0, 10)}, {Eigen::Vector3d(1, 0.5, 5)}};
  cv::Mat map;
  LabelProjectionOptions options;
  const int n = RenderLabelMap(points, Eigen::Isometry3d::Identity(), cam, options, &map);
  EXPECT_EQ(n, 2);
  EXPECT_FLOAT_EQ(map.at<float>(10, 20), 100 * 0.5 / 10);
  EXPECT_FLOAT_EQ(map.at<float>(10 + 10, 20 + 20), 100 * 0.5 / 5);  // u = 100*1/5+20 = 40, v = 20
  EXPECT_EQ(cv::countNonZero(map), 2);
}

TEST(LabelMap, UsesThePoseAndDropsOutOfViewPoints) {
  const StereoCamera cam = SmallCamera();
  Eigen::Isometry3d T_world_camera = Eigen::Isometry3d::Identity();
  T_world_camera.translation() = Eigen::Vector3d(0, 0, 5);  // camera moved 5 m forward
  std::vector<LabelPoint> points = {{Eigen::Vector3d(0, 0, 10)},   // now 5 m ahead
                                    {Eigen::Vector3d(0, 0, 4)},    // behind the camera
                                    {Eigen::Vector3d(50, 0, 10)}};  // far outside the image
  cv::Mat map;
  EXPECT_EQ(RenderLabelMap(points, T_world_camera, cam, LabelProjectionOptions(), &map), 1);
  EXPECT_FLOAT_EQ(map.at<float>(10, 20), 100 * 0.5 / 5);
}

TEST(LabelMap, NearerPointHidesFartherNeighbour) {
  const StereoCamera cam = SmallCamera();
  // Far point at pixel (20,10); near point one pixel to the right: the far one is occluded.
  std::vector<LabelPoint> points = {{Eigen::Vector3d(0, 0, 20)}, {Eigen::Vector3d(0.02, 0, 2)}};
  cv::Mat map;
  LabelProjectionOptions options;
  EXPECT_EQ(RenderLabelMap(points, Eigen::Isometry3d::Identity(), cam, options, &map), 1);
  EXPECT_FLOAT_EQ(map.at<float>(10, 20), 0.f);
  EXPECT_FLOAT_EQ(map.at<float>(10, 21), 25.f);
  options.occlusion_radius = 0;  // without splats both survive
  EXPECT_EQ(RenderLabelMap(points, Eigen::Isometry3d::Identity(), cam, options, &map), 2);
}

TEST(LabelMap, OptionsCheck) {
  LabelProjectionOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_disparity = 300;
  EXPECT_THROW(options.Check(), Error);
}

TEST(LabelStatistics, CountsAndAccuracyByHand) {
  cv::Mat labels(2, 3, CV_32F, cv::Scalar(0)), gt(2, 3, CV_32F, cv::Scalar(0));
  labels.at<float>(0, 0) = 10.5f;  gt.at<float>(0, 0) = 10.0f;   // err 0.5: <1px, not <3% (0.3)
  labels.at<float>(0, 1) = 50.0f;  gt.at<float>(0, 1) = 51.2f;   // err 1.2: not <1px, <3% (1.536)
  labels.at<float>(1, 2) = 20.0f;  gt.at<float>(1, 2) = 20.1f;   // err 0.1: both
  labels.at<float>(1, 0) = 7.0f;                                 // no GT: counted, not compared
  LabelStatistics stats;
  stats.AddFrame(labels, gt);
  cv::Mat one(2, 3, CV_32F, cv::Scalar(0));
  one.at<float>(0, 0) = 3.f;
  stats.AddFrame(one);
  EXPECT_EQ(stats.frames(), 2);
  EXPECT_DOUBLE_EQ(stats.mean_labels_per_frame(), 2.5);
  EXPECT_EQ(stats.min_labels_per_frame(), 1);
  EXPECT_EQ(stats.compared(), 3);
  EXPECT_DOUBLE_EQ(stats.share_within_1px(), 2.0 / 3);
  EXPECT_DOUBLE_EQ(stats.share_within_3_percent(), 2.0 / 3);
  EXPECT_NEAR(stats.mean_absolute_error(), (0.5 + 1.2 + 0.1) / 3, 1e-5);
  EXPECT_EQ(stats.ToJson()["labels_per_frame_min"], 1);

  // Merging the frames one sequence at a time gives the statistics of all frames together.
  LabelStatistics first, second, merged;
  first.AddFrame(labels, gt);
  second.AddFrame(one);
  merged.Merge(LabelStatistics{});  // an empty one changes nothing (its min of 0 included)
  merged.Merge(first);
  merged.Merge(second);
  EXPECT_EQ(merged.ToJson(), stats.ToJson());
}

TEST(LabelMap, DepthEdgesAreNotLabelled) {
  const StereoCamera cam = SmallCamera();
  // A near point (5 m) 2 px left of a far point (20 m), both in front of the camera:
  // u = 100 * X / Z + 20, so X = 0 at 5 m -> u = 20, X = 0.4 at 20 m -> u = 22.
  const std::vector<LabelPoint> points = {{Eigen::Vector3d(0, 0, 5)}, {Eigen::Vector3d(0.4, 0, 20)}};
  LabelProjectionOptions options;
  options.occlusion_radius = 1;  // the far point is not hidden ...
  cv::Mat map;
  EXPECT_EQ(RenderLabelMap(points, Eigen::Isometry3d::Identity(), cam, options, &map), 2);
  options.edge_radius = 3;       // ... but the near one sits on a depth edge
  EXPECT_EQ(RenderLabelMap(points, Eigen::Isometry3d::Identity(), cam, options, &map), 1);
  EXPECT_FLOAT_EQ(map.at<float>(10, 22), 100 * 0.5 / 20);
  EXPECT_EQ(map.at<float>(10, 20), 0.f);
  // Points on one surface (within edge_margin) are no edge.
  const std::vector<LabelPoint> surface = {{Eigen::Vector3d(0, 0, 10)}, {Eigen::Vector3d(0.2, 0, 10.5)}};
  EXPECT_EQ(RenderLabelMap(surface, Eigen::Isometry3d::Identity(), cam, options, &map), 2);
  options.edge_radius = 11;
  EXPECT_THROW(options.Check(), Error);
}
