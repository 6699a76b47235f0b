// KITTI odometry metrics, ATE and RPE against hand-computed cases: straight
// lines where the devkit's segment search has a closed form, a scaled
// estimate, a constant rotation drift, missing frames, and the real KITTI 04 GT.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/eval_odometry.h"
#include "core/lie.h"
#include "core/plot.h"
#include "core/trajectory.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// GT: `frames` poses 1 m apart along +z, identity orientation, timestamp = index.
Trajectory StraightLine(int frames, double step = 1.0) {
  Trajectory t;
  for (int i = 0; i < frames; ++i) {
    StampedPose p;
    p.timestamp = i;
    p.T_world_camera.translation() = Eigen::Vector3d(0, 0, step * i);
    t.poses.push_back(p);
  }
  return t;
}

// Number of devkit segments of length L on a 1 m-step straight line of N frames:
// the last frame of a segment starting at f is f + L + 1 (first distance > f + L),
// so f runs over 0, 10, ... <= N - 2 - L.
int SegmentsOnLine(int frames, int length) { return length + 1 <= frames - 1 ? (frames - 2 - length) / 10 + 1 : 0; }

Trajectory KittiSequence04() {
  return ReadTrajectory(std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/04.txt");
}

TEST(EvalOdometry, GroundTruthAgainstItselfGivesZeros) {
  const Trajectory gt = KittiSequence04();
  for (const AlignmentMode mode : {AlignmentMode::kNone, AlignmentMode::kSE3, AlignmentMode::kSim3}) {
    OdometryEvalOptions options;
    options.align = mode;
    const OdometryMetrics m = EvaluateOdometry(gt, gt, options);
    EXPECT_GT(m.segments, 0);
    EXPECT_NEAR(m.t_rel, 0.0, 1e-6);
    EXPECT_NEAR(m.r_rel, 0.0, 1e-4);  // acos near 1 is ill-conditioned
    EXPECT_NEAR(m.ate_rmse, 0.0, 1e-6);
    EXPECT_NEAR(m.rpe_trans_rmse, 0.0, 1e-9);
    EXPECT_NEAR(m.alignment.scale, 1.0, 1e-9);
    EXPECT_EQ(m.gt_frames, 271);
    EXPECT_EQ(m.matched_frames, 271);
    EXPECT_TRUE(m.missing_frames.empty());
    EXPECT_NEAR(m.gt_path_length, m.est_path_length, 1e-6);
  }
}

TEST(EvalOdometry, SegmentCountsFollowTheDevkitSearch) {
  const int frames = 1001;
  const Trajectory gt = StraightLine(frames);
  const OdometryMetrics m = EvaluateOdometry(gt, gt, {});
  int expected_total = 0;
  ASSERT_EQ(m.per_length.size(), 8u);
  for (int k = 0; k < 8; ++k) {
    const int length = 100 * (k + 1);
    EXPECT_EQ(m.per_length[k].segments, SegmentsOnLine(frames, length)) << length;
    expected_total += SegmentsOnLine(frames, length);
  }
  EXPECT_EQ(m.segments, expected_total);
  EXPECT_EQ(m.segments, 90 + 80 + 70 + 60 + 50 + 40 + 30 + 20);
}

TEST(EvalOdometry, ScaledEstimateUnalignedAndSim3) {
  const int frames = 1001;
  const Trajectory gt = StraightLine(frames);
  const Trajectory est = StraightLine(frames, 1.1);  // 10 % too long
  // Unaligned: each segment's error is 0.1 * (L + 1) m over L m.
  double expected_sum = 0.0;
  int count = 0;
  for (int length = 100; length <= 800; length += 100) {
    const int n = SegmentsOnLine(frames, length);
    expected_sum += n * 0.1 * (length + 1) / length;
    count += n;
  }
  const OdometryMetrics raw = EvaluateOdometry(gt, est, {});
  EXPECT_NEAR(raw.t_rel, 100.0 * expected_sum / count, 1e-9);
  EXPECT_NEAR(raw.t_rel, 10.0, 0.5);  // ~10 % as intuition says
  EXPECT_NEAR(raw.r_rel, 0.0, 1e-9);
  EXPECT_NEAR(raw.per_length[0].t_rel, 100.0 * 0.1 * 101.0 / 100.0, 1e-9);
  EXPECT_NEAR(raw.rpe_trans_rmse, 0.1, 1e-9);  // 1.1 m vs 1 m per frame
  EXPECT_GT(raw.ate_rmse, 10.0);

  OdometryEvalOptions sim3;
  sim3.align = AlignmentMode::kSim3;
  const OdometryMetrics aligned = EvaluateOdometry(gt, est, sim3);
  EXPECT_NEAR(aligned.alignment.scale, 1.0 / 1.1, 1e-12);
  EXPECT_NEAR(aligned.ate_rmse, 0.0, 1e-9);
  EXPECT_NEAR(aligned.t_rel, 0.0, 1e-9);  // KITTI metrics on the aligned estimate
  EXPECT_NEAR(aligned.rpe_trans_rmse, 0.0, 1e-9);

  OdometryEvalOptions se3;
  se3.align = AlignmentMode::kSE3;
  const OdometryMetrics rigid = EvaluateOdometry(gt, est, se3);
  EXPECT_DOUBLE_EQ(rigid.alignment.scale, 1.0);
  EXPECT_NEAR(rigid.t_rel, raw.t_rel, 1e-9);  // rigid alignment cannot fix scale
  EXPECT_LT(rigid.ate_rmse, raw.ate_rmse);
}

TEST(EvalOdometry, Sim3RecoversScaledAndMovedRealTrajectory) {
  const Trajectory gt = KittiSequence04();
  Similarity3 gauge;
  gauge.scale = 0.37;
  gauge.rotation = ExpSO3(Eigen::Vector3d(0.2, 1.0, -0.4));
  gauge.translation = Eigen::Vector3d(5, -2, 30);
  Trajectory est = gt;
  for (StampedPose& p : est.poses) p.T_world_camera = gauge.Apply(p.T_world_camera);
  OdometryEvalOptions options;
  options.align = AlignmentMode::kSim3;
  const OdometryMetrics m = EvaluateOdometry(gt, est, options);
  EXPECT_NEAR(m.alignment.scale, 1.0 / 0.37, 1e-9);
  EXPECT_NEAR(m.ate_rmse, 0.0, 1e-6);
  EXPECT_NEAR(m.t_rel, 0.0, 1e-6);
  // Without alignment the KITTI metric sees the 0.37 scale: ~63 % error.
  const OdometryMetrics raw = EvaluateOdometry(gt, est, {});
  EXPECT_NEAR(raw.t_rel, 63.0, 1.5);
  EXPECT_NEAR(raw.r_rel, 0.0, 1e-3);  // relative rotations are gauge-free
}

TEST(EvalOdometry, ConstantRotationDrift) {
  // Estimate turns by w rad per frame about y while moving 1 m along its own z:
  // est_i = D^i with D = [R_y(w) | (0,0,1)]. For a segment of n = L + 1 frames
  // the error is E = D^-n G^n: angle n w, translation norm |n e_z - sum_k R_y(kw) e_z|.
  const int frames = 1001;
  const double w = 0.001;
  const Trajectory gt = StraightLine(frames);
  Trajectory est = gt;
  Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
  step.linear() = Eigen::AngleAxisd(w, Eigen::Vector3d::UnitY()).toRotationMatrix();
  step.translation() = Eigen::Vector3d(0, 0, 1);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int i = 0; i < frames; ++i) {
    est.poses[i].T_world_camera = pose;
    pose = pose * step;
  }
  double r_sum = 0.0, t_sum = 0.0;
  int count = 0;
  for (int length = 100; length <= 800; length += 100) {
    const int n = length + 1;
    double sx = 0.0, sz = 0.0;
    for (int k = 0; k < n; ++k) {
      sx += std::sin(k * w);
      sz += std::cos(k * w);
    }
    const double translation = std::hypot(sx, n - sz);
    const int segments = SegmentsOnLine(frames, length);
    r_sum += segments * n * w / length;
    t_sum += segments * translation / length;
    count += segments;
  }
  const OdometryMetrics m = EvaluateOdometry(gt, est, {});
  EXPECT_NEAR(m.r_rel, 100.0 * kRadToDeg * r_sum / count, 1e-6);
  EXPECT_NEAR(m.t_rel, 100.0 * t_sum / count, 1e-6);
  // ~0.1 rad per 100 m = 5.73 deg/100 m (slightly more because n = L + 1).
  EXPECT_NEAR(m.r_rel, 5.73, 0.1);
  EXPECT_NEAR(m.rpe_rot_rmse, w * kRadToDeg, 1e-6);
  EXPECT_NEAR(m.rpe_trans_rmse, 0.0, 1e-9);  // each step itself is 1 m forward
}

TEST(EvalOdometry, MissingFramesAreReportedAndSkipped) {
  const Trajectory gt = StraightLine(1001);
  Trajectory est;
  for (const StampedPose& p : gt.poses) {
    const int i = static_cast<int>(p.timestamp);
    if ((i >= 5 && i <= 9) || i == 500 || i >= 990) continue;
    est.poses.push_back(p);
  }
  const OdometryMetrics m = EvaluateOdometry(gt, est, {});
  std::vector<int> expected = {5, 6, 7, 8, 9, 500};
  for (int i = 990; i <= 1000; ++i) expected.push_back(i);
  EXPECT_EQ(m.missing_frames, expected);
  EXPECT_EQ(m.matched_frames, 1001 - static_cast<int>(expected.size()));
  EXPECT_EQ(m.unmatched_est_frames, 0);
  EXPECT_NEAR(m.t_rel, 0.0, 1e-12);
  // Segments starting at 500 are gone, and those ending at a missing frame.
  const OdometryMetrics full = EvaluateOdometry(gt, gt, {});
  EXPECT_LT(m.segments, full.segments);
  EXPECT_GT(m.segments, 0);
  const nlohmann::json j = OdometryMetricsToJson(m);
  EXPECT_EQ(j["missing_frames"].get<int>(), static_cast<int>(expected.size()));
  EXPECT_EQ(j["missing_frame_indices"].get<std::vector<int>>(), expected);
  EXPECT_EQ(j["missing_frame_timestamps"].get<std::vector<double>>().at(5), 500.0);
  EXPECT_NE(FormatOdometryMetrics(m).find("5-9, 500, 990-1000"), std::string::npos) << FormatOdometryMetrics(m);
}

TEST(EvalOdometry, TimestampAssociationTolerance) {
  Trajectory gt = StraightLine(300);
  Trajectory est = gt;
  for (StampedPose& p : gt.poses) p.timestamp = 1000.0 + 0.1 * p.timestamp;
  for (size_t i = 0; i < est.size(); ++i) est.poses[i].timestamp = gt.poses[i].timestamp + 0.004;
  const std::vector<int> match = AssociateByTimestamp(gt, est, 0.01);
  for (size_t i = 0; i < match.size(); ++i) EXPECT_EQ(match[i], static_cast<int>(i));
  // Shifted by 0.05 s (half a frame): nothing within 0.01 s.
  for (size_t i = 0; i < est.size(); ++i) est.poses[i].timestamp = gt.poses[i].timestamp + 0.05;
  EXPECT_THROW(EvaluateOdometry(gt, est, {}), Error);
  // Each estimated pose is used once even when the tolerance spans two GT poses.
  OdometryEvalOptions wide;
  wide.max_time_difference = 0.2;
  const std::vector<int> wide_match = AssociateByTimestamp(gt, est, wide.max_time_difference);
  std::vector<int> used;
  for (const int j : wide_match) {
    if (j >= 0) used.push_back(j);
  }
  std::sort(used.begin(), used.end());
  EXPECT_EQ(std::adjacent_find(used.begin(), used.end()), used.end());
}

TEST(EvalOdometry, RejectsMalformedInput) {
  Trajectory gt = StraightLine(50);
  Trajectory est = gt;
  std::swap(est.poses[3].timestamp, est.poses[4].timestamp);
  EXPECT_THROW(EvaluateOdometry(gt, est, {}), Error);  // not increasing
  EXPECT_THROW(EvaluateOdometry(gt, Trajectory{}, {}), Error);
  OdometryEvalOptions bad;
  bad.step_size = 0;
  EXPECT_THROW(bad.Check(), Error);
  bad = {};
  bad.segment_lengths = {100, -5};
  EXPECT_THROW(bad.Check(), Error);
  bad = {};
  bad.rpe_delta_frames = 0;
  EXPECT_THROW(bad.Check(), Error);
}

TEST(EvalOdometry, ShortPathHasNoSegmentsButOtherMetrics) {
  const Trajectory gt = StraightLine(50);  // 49 m < 100 m
  const OdometryMetrics m = EvaluateOdometry(gt, gt, {});
  EXPECT_EQ(m.segments, 0);
  EXPECT_TRUE(std::isnan(m.t_rel));
  const nlohmann::json j = OdometryMetricsToJson(m);
  EXPECT_TRUE(j["t_rel"].is_null());
  EXPECT_EQ(j["ate_rmse"].get<double>(), 0.0);
}

// Zero segments for want of estimated poses is not a short GT path: the reason says which it is.
TEST(EvalOdometry, SegmentsDroppedForMissingEstimateFramesAreCountedAndNamed) {
  const Trajectory gt = StraightLine(300);  // 299 m: segments of 100 and 200 m
  Trajectory est;
  for (int i = 0; i < 100; ++i) est.poses.push_back(gt.poses[i]);  // every segment ends at frame >= 101
  const OdometryMetrics m = EvaluateOdometry(gt, est, {});
  EXPECT_EQ(m.segments, 0);
  EXPECT_EQ(m.segments_without_estimate, SegmentsOnLine(300, 100) + SegmentsOnLine(300, 200));
  EXPECT_EQ(m.segments_without_estimate, 30);
  const std::string table = FormatOdometryMetrics(m);
  EXPECT_NE(table.find("the estimate lacks the first or last frame of all 30 segments"), std::string::npos) << table;
  EXPECT_EQ(table.find("no longer than"), std::string::npos) << table;
  EXPECT_EQ(OdometryMetricsToJson(m)["segments_without_estimate"].get<int>(), 30);
  // A short GT path keeps its own reason; a complete estimate drops nothing.
  const OdometryMetrics short_path = EvaluateOdometry(StraightLine(50), StraightLine(50), {});
  EXPECT_EQ(short_path.segments_without_estimate, 0);
  EXPECT_NE(NoKittiSegmentsReason(short_path).find("GT path is no longer than the shortest segment"),
            std::string::npos);
  EXPECT_EQ(EvaluateOdometry(gt, gt, {}).segments_without_estimate, 0);
  // MissingFramesAreReportedAndSkipped's gaps: the dropped segments are what the full estimate has more.
  Trajectory gappy;
  for (const StampedPose& p : StraightLine(1001).poses) {
    const int i = static_cast<int>(p.timestamp);
    if (!((i >= 5 && i <= 9) || i == 500 || i >= 990)) gappy.poses.push_back(p);
  }
  const OdometryMetrics partial = EvaluateOdometry(StraightLine(1001), gappy, {});
  EXPECT_EQ(partial.segments + partial.segments_without_estimate,
            EvaluateOdometry(StraightLine(1001), StraightLine(1001), {}).segments);
}

TEST(EvalOdometry, JsonHasRequiredKeys) {
  OdometryEvalOptions options;
  options.align = AlignmentMode::kSim3;
  const OdometryMetrics m = EvaluateOdometry(StraightLine(400), StraightLine(400, 2.0), options);
  const nlohmann::json j = OdometryMetricsToJson(m);
  for (const char* key : {"t_rel", "r_rel", "ate_rmse", "scale", "frames", "missing_frames", "align",
                          "rpe_trans_rmse", "rpe_rot_rmse_deg", "per_length", "kitti_metrics_on"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["align"], "sim3");
  EXPECT_NEAR(j["scale"].get<double>(), 0.5, 1e-12);
}

TEST(EvalOdometry, WritesBothPlots) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("eval_plots"));
  fs::remove_all(dir);
  const Trajectory gt = KittiSequence04();
  Trajectory est = gt;
  for (StampedPose& p : est.poses) p.T_world_camera.translation() *= 1.05;
  OdometryEvalOptions options;
  const OdometryMetrics m = EvaluateOdometry(gt, est, options);
  EXPECT_EQ(WriteOdometryPlots(dir.string(), gt, AlignedMatchedEstimate(gt, est, options, m), m).size(), 2u);
  const cv::Mat top = cv::imread((dir / "trajectory_xz.png").string());
  const cv::Mat segments = cv::imread((dir / "segment_errors.png").string());
  ASSERT_FALSE(top.empty());
  ASSERT_FALSE(segments.empty());
  EXPECT_EQ(top.cols, 900);
  EXPECT_EQ(segments.cols, 1300);
  // A GT path below 100 m has no segments: only the top view is written.
  fs::remove_all(dir);
  const Trajectory short_gt = StraightLine(50);
  const OdometryMetrics short_m = EvaluateOdometry(short_gt, short_gt, options);
  const auto written = WriteOdometryPlots(dir.string(), short_gt, short_gt, short_m);
  ASSERT_EQ(written.size(), 1u);
  EXPECT_TRUE(fs::exists(dir / "trajectory_xz.png"));
  EXPECT_FALSE(fs::exists(dir / "segment_errors.png"));
  fs::remove_all(dir);
}

// A run without segments must not leave an earlier run's segment_errors.png beside its own top view.
TEST(EvalOdometry, RunWithoutSegmentsRemovesAnEarlierSegmentPlot) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("eval_plots_stale"));
  fs::remove_all(dir);
  const Trajectory gt = StraightLine(300);
  const OdometryMetrics m = EvaluateOdometry(gt, gt, {});
  ASSERT_EQ(WriteOdometryPlots(dir.string(), gt, gt, m).size(), 2u);
  ASSERT_TRUE(fs::exists(dir / "segment_errors.png"));
  const Trajectory short_gt = StraightLine(50);
  const OdometryMetrics short_m = EvaluateOdometry(short_gt, short_gt, {});
  EXPECT_EQ(WriteOdometryPlots(dir.string(), short_gt, short_gt, short_m).size(), 1u);
  EXPECT_TRUE(fs::exists(dir / "trajectory_xz.png"));
  EXPECT_FALSE(fs::exists(dir / "segment_errors.png"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace dvso

namespace dvso {
namespace {

TEST(Plot, NiceTicksUseOneTwoFiveSteps) {
  EXPECT_EQ(NiceTicks(0.0, 10.0, 5), (std::vector<double>{0, 2, 4, 6, 8, 10}));
  const std::vector<double> ticks = NiceTicks(-0.37, 0.81, 8);  // raw step 0.1475 -> 0.2
  ASSERT_EQ(ticks.size(), 6u);
  EXPECT_NEAR(ticks.front(), -0.2, 1e-12);
  EXPECT_NEAR(ticks.back(), 0.8, 1e-12);
  EXPECT_EQ(ticks[1], 0.0);
  EXPECT_TRUE(NiceTicks(1.0, 1.0, 5).empty());
}

TEST(Plot, RejectsEmptyOrInconsistentSeries) {
  PlotSeries empty;
  EXPECT_THROW(RenderPlot({empty}, PlotOptions{}), Error);
  PlotSeries bad;
  bad.x = {1, 2, 3};
  bad.y = {1, 2};
  EXPECT_THROW(RenderPlot({bad}, PlotOptions{}), Error);
  PlotSeries ok;
  ok.x = {0, 1, 2};
  ok.y = {0, 1, NAN};
  const cv::Mat image = RenderPlot({ok}, PlotOptions{});
  EXPECT_EQ(image.type(), CV_8UC3);
  EXPECT_EQ(image.size(), cv::Size(900, 700));
}

// The x tick labels hang below their tick marks: a label drawn over its mark turned "0.2" into "0!2".
TEST(Plot, XTickLabelsSitBelowTheirTickMarks) {
  PlotSeries line;
  line.x = {0.0, 1.0};
  line.y = {0.0, 1.0};
  const cv::Mat image = RenderPlot({line}, PlotOptions{});
  auto is_dark = [&](int row, int col) {
    const cv::Vec3b bgr = image.at<cv::Vec3b>(row, col);
    return bgr[0] < 128 && bgr[1] < 128 && bgr[2] < 128;
  };
  // Only the middle half of the columns: the y tick labels left of the axes do not count.
  const int first_col = image.cols / 4, last_col = 3 * image.cols / 4;
  auto dark_in_row = [&](int row) {
    int count = 0;
    for (int col = first_col; col < last_col; ++col) count += is_dark(row, col);
    return count;
  };
  // The axes' bottom edge is the lowest row that is black nearly all across.
  int axis_row = -1;
  for (int row = image.rows - 1; row >= 0 && axis_row < 0; --row) {
    if (dark_in_row(row) > (last_col - first_col) * 9 / 10) axis_row = row;
  }
  ASSERT_GT(axis_row, 0);
  ASSERT_LT(axis_row + 30, image.rows);
  const int ticks_in_view = static_cast<int>(NiceTicks(0.0, 1.0, 8).size());
  for (int row = axis_row + 1; row <= axis_row + 6; ++row) {
    EXPECT_LE(dark_in_row(row), ticks_in_view) << "row " << row - axis_row << " below the axis holds more than the marks";
  }
  int label_pixels = 0;
  for (int row = axis_row + 8; row <= axis_row + 25; ++row) label_pixels += dark_in_row(row);
  EXPECT_GT(label_pixels, 5 * ticks_in_view);  // the labels are there, below the marks
}

}  // namespace
}  // namespace dvso
