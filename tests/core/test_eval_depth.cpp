// Depth metrics on tiny hand-made maps against hand-computed values, crops,
// clamping, median scaling, disparity conversion and the folder evaluation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "core/eval_depth.h"
#include "core/kitti_raw_calibration.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace dvso {
namespace {

cv::Mat Map(int rows, int cols, std::initializer_list<float> values) {
  cv::Mat m(rows, cols, CV_32F);
  auto it = values.begin();
  for (int v = 0; v < rows; ++v) {
    for (int u = 0; u < cols; ++u) m.at<float>(v, u) = *it++;
  }
  return m;
}

DepthEvalOptions DepthOnly() {
  DepthEvalOptions o;
  o.pred_kind = o.gt_kind = MapKind::kDepth;
  return o;
}

TEST(EvalDepth, HandComputedMetrics) {
  // Valid pairs (pred, gt): (12, 10), (20, 20), (30, 40); GT 0 is invalid.
  const cv::Mat gt = Map(2, 2, {10, 20, 0, 40});
  const cv::Mat pred = Map(2, 2, {12, 20, 5, 30});
  const DepthMetrics m = ComputeDepthMetrics(pred, gt, DepthOnly());
  EXPECT_EQ(m.valid_pixels, 3);
  EXPECT_NEAR(m.abs_rel, (0.2 + 0.0 + 0.25) / 3.0, 1e-12);
  EXPECT_NEAR(m.sq_rel, (4.0 / 10.0 + 0.0 + 100.0 / 40.0) / 3.0, 1e-12);
  EXPECT_NEAR(m.rmse, std::sqrt(104.0 / 3.0), 1e-12);
  EXPECT_NEAR(m.rmse_log, std::sqrt((std::pow(std::log(1.2), 2) + std::pow(std::log(0.75), 2)) / 3.0), 1e-7);
  EXPECT_NEAR(m.a1, 2.0 / 3.0, 1e-12);  // ratios 1.2, 1, 1.333
  EXPECT_NEAR(m.a2, 1.0, 1e-12);
  EXPECT_NEAR(m.a3, 1.0, 1e-12);
}

TEST(EvalDepth, PerfectPredictionGivesZeroErrors) {
  const cv::Mat gt = Map(1, 4, {3, 7.5, 15, 60});
  const DepthMetrics m = ComputeDepthMetrics(gt.clone(), gt, DepthOnly());
  EXPECT_EQ(m.abs_rel, 0.0);
  EXPECT_EQ(m.rmse, 0.0);
  EXPECT_EQ(m.rmse_log, 0.0);
  EXPECT_EQ(m.a1, 1.0);
}

TEST(EvalDepth, ClampsPredictionsAndMasksGtRange) {
  // GT 90 m is outside (min, max) = (1e-3, 80): excluded. Predictions 100 -> 80, 0 -> 1e-3.
  const cv::Mat gt = Map(1, 3, {40, 90, 2});
  const cv::Mat pred = Map(1, 3, {100, 5, 0});
  const DepthMetrics m = ComputeDepthMetrics(pred, gt, DepthOnly());
  EXPECT_EQ(m.valid_pixels, 2);
  EXPECT_NEAR(m.abs_rel, (40.0 / 40.0 + (2.0 - 1e-3) / 2.0) / 2.0, 1e-9);
  EXPECT_NEAR(m.rmse, std::sqrt((40.0 * 40.0 + (2.0 - 1e-3) * (2.0 - 1e-3)) / 2.0), 1e-9);
  // Infinite predicted depth (zero disparity) is clamped to max_depth too.
  const cv::Mat far = Map(1, 3, {INFINITY, 5, 2});
  EXPECT_NEAR(ComputeDepthMetrics(far, gt, DepthOnly()).abs_rel, (40.0 / 40.0 + 0.0) / 2.0, 1e-9);
}

TEST(EvalDepth, MedianScalingRemovesGlobalScale) {
  const cv::Mat gt = Map(1, 4, {4, 8, 12, 20});
  const cv::Mat pred = gt / 3.0;
  DepthEvalOptions o = DepthOnly();
  o.median_scaling = true;
  const DepthMetrics m = ComputeDepthMetrics(pred, gt, o);
  EXPECT_NEAR(m.scale, 3.0, 1e-6);  // median of an even count: mean of the middle two
  EXPECT_NEAR(m.abs_rel, 0.0, 1e-6);
  EXPECT_NEAR(m.a1, 1.0, 1e-12);
  o.median_scaling = false;
  EXPECT_NEAR(ComputeDepthMetrics(pred, gt, o).abs_rel, 2.0 / 3.0, 1e-6);
}

TEST(EvalDepth, CropRegionsMatchMonodepthFractions) {
  // KITTI-like 375 x 1242: int(0.40810811*375)=153, int(0.99189189*375)=371,
  // int(0.03594771*1242)=44, int(0.96405229*1242)=1197.
  EXPECT_EQ(DepthCropRegion(DepthCrop::kGarg, 1242, 375), cv::Rect(44, 153, 1197 - 44, 371 - 153));
  // int(0.3324324*375)=124, int(0.91351351*375)=342, int(0.0359477*1242)=44.
  EXPECT_EQ(DepthCropRegion(DepthCrop::kEigen, 1242, 375), cv::Rect(44, 124, 1197 - 44, 342 - 124));
  EXPECT_EQ(DepthCropRegion(DepthCrop::kNone, 1242, 375), cv::Rect(0, 0, 1242, 375));
}

TEST(EvalDepth, CropExcludesPixelsOutside) {
  // 100 x 100 map, all correct except a badly wrong top row (outside both crops).
  cv::Mat gt(100, 100, CV_32F, cv::Scalar(10.0f));
  cv::Mat pred = gt.clone();
  pred.row(0).setTo(20.0f);
  DepthEvalOptions o = DepthOnly();
  const DepthMetrics none = ComputeDepthMetrics(pred, gt, o);
  EXPECT_EQ(none.valid_pixels, 10000);
  EXPECT_NEAR(none.abs_rel, 100.0 / 10000.0, 1e-12);
  o.crop = DepthCrop::kGarg;  // rows 40..98, cols 3..95
  const DepthMetrics garg = ComputeDepthMetrics(pred, gt, o);
  EXPECT_EQ(garg.valid_pixels, (99 - 40) * (96 - 3));
  EXPECT_EQ(garg.abs_rel, 0.0);
}

TEST(EvalDepth, DisparityConversionAndResize) {
  const cv::Mat disparity = Map(1, 3, {10, 0, -1});
  const cv::Mat depth = DisparityToDepth(disparity, 386.0, 0.0f);
  EXPECT_FLOAT_EQ(depth.at<float>(0, 0), 38.6f);
  EXPECT_EQ(depth.at<float>(0, 1), 0.0f);
  EXPECT_EQ(depth.at<float>(0, 2), 0.0f);
  // A half-width disparity map doubles its values when resized to full width.
  const cv::Mat half(4, 5, CV_32F, cv::Scalar(7.0f));
  const cv::Mat full = ResizePrediction(half, MapKind::kDisparity, cv::Size(10, 8));
  EXPECT_EQ(full.size(), cv::Size(10, 8));
  EXPECT_FLOAT_EQ(full.at<float>(3, 6), 14.0f);
  const cv::Mat depth_full = ResizePrediction(half, MapKind::kDepth, cv::Size(10, 8));
  EXPECT_FLOAT_EQ(depth_full.at<float>(3, 6), 7.0f);
}

TEST(EvalDepth, OptionsCheck) {
  DepthEvalOptions o;  // disparity kinds without fxb
  EXPECT_THROW(o.Check(), Error);
  o.fxb = 380.0;
  EXPECT_NO_THROW(o.Check());
  o.max_depth = o.min_depth;
  EXPECT_THROW(o.Check(), Error);
  EXPECT_THROW(ParseDepthCrop("square"), Error);
  EXPECT_THROW(ParseMapKind("normals"), Error);
  EXPECT_EQ(ParseDepthCrop("Garg"), DepthCrop::kGarg);
}

TEST(EvalDepth, SplitLineFxBIsTheCameraFocalTimesTheColourBaseline) {
  // A raw day with KITTI's layout: colour camera 02 6 cm left of camera 00, 03 0.47 m right of it
  // (P_rect_0X = K [I | t], t_x = -fx * x_centre), and fx 700 px.
  const std::string dir = dvso::testing::ScratchPath("split_fxb");
  std::filesystem::create_directories(dir);
  std::ofstream(dir + "/calib_cam_to_cam.txt")
      << "P_rect_00: 700 0 30 0 0 700 20 0 0 0 1 0\n"
      << "P_rect_01: 700 0 30 -378 0 700 20 0 0 0 1 0\n"
      << "P_rect_02: 700 0 30 42 0 700 20 0 0 0 1 0\n"
      << "P_rect_03: 700 0 30 -329 0 700 20 0 0 0 1 0\n";
  const RawCameraCalibration calibration(dir);
  EXPECT_NEAR(SplitLineFxB(calibration, 2), 700.0 * (0.47 + 0.06), 1e-9);  // not the grey pair's 0.54 m
  EXPECT_NEAR(SplitLineFxB(calibration, 3), 700.0 * 0.53, 1e-9);
  EXPECT_THROW(SplitLineFxB(calibration, 0), Error);
}

TEST(EvalDepth, KittiFocalByWidth) {
  EXPECT_DOUBLE_EQ(KittiFocalLengthForWidth(1242), 721.5377);
  EXPECT_DOUBLE_EQ(KittiFocalLengthForWidth(1224), 707.0493);
  // 2011_09_30 (KITTI odometry 04-10, 1226 x 370): P0[0][0] of their calib.txt.
  EXPECT_DOUBLE_EQ(KittiFocalLengthForWidth(1226), 707.0912);
  EXPECT_DOUBLE_EQ(KittiFocalLengthForWidth(1238), 718.3351);
  EXPECT_DOUBLE_EQ(KittiFocalLengthForWidth(1241), 718.856);
  EXPECT_THROW(KittiFocalLengthForWidth(640), Error);
  DepthEvalOptions o;
  o.kitti_focal_by_width = true;
  EXPECT_NO_THROW(o.Check());
  o.fxb = 300.0;
  EXPECT_THROW(o.Check(), Error);  // ambiguous
}

TEST(EvalDepth, AverageIsOverImagesNotPixels) {
  DepthMetrics a, b;
  a.abs_rel = 0.1;
  a.valid_pixels = 1000;
  b.abs_rel = 0.3;
  b.valid_pixels = 10;
  DepthMetrics empty;
  empty.valid_pixels = 0;
  empty.abs_rel = NAN;
  const DepthMetrics mean = AverageDepthMetrics({a, b, empty});
  EXPECT_NEAR(mean.abs_rel, 0.2, 1e-12);
  EXPECT_EQ(mean.valid_pixels, 1010);
}

// Writes a KITTI uint16 PNG (round(value * 256)) without going through the library writer.
void WriteUint16(const fs::path& path, const cv::Mat& values) {
  cv::Mat raw;
  values.convertTo(raw, CV_16U, 256.0);
  ASSERT_TRUE(cv::imwrite(path.string(), raw));
}

struct Folders {
  fs::path root, pred, gt;
  explicit Folders(const std::string& name) {
    root = fs::path(dvso::testing::ScratchPath("eval_depth_" + name));
    fs::remove_all(root);
    pred = root / "pred";
    gt = root / "gt";
    fs::create_directories(pred);
    fs::create_directories(gt);
  }
  ~Folders() { fs::remove_all(root); }
};

TEST(EvalDepth, FolderOfDisparityMaps) {
  Folders f("ok");
  // GT disparity 20 px everywhere except an invalid column; fxb = 400 -> 20 m.
  cv::Mat gt(6, 8, CV_32F, cv::Scalar(20.0f));
  gt.col(0).setTo(0.0f);
  WriteUint16(f.gt / "a.png", gt);
  WriteUint16(f.gt / "b.png", gt);
  // a: perfect at half resolution (10 px at width 4 -> 20 px at width 8); b: 25 px -> 16 m.
  WriteUint16(f.pred / "a.png", cv::Mat(3, 4, CV_32F, cv::Scalar(10.0f)));
  WriteUint16(f.pred / "b.png", cv::Mat(6, 8, CV_32F, cv::Scalar(25.0f)));
  DepthEvalOptions o;
  o.fxb = 400.0;
  const DepthEvalResult r = EvaluateDepthFolders(f.pred.string(), f.gt.string(), o);
  ASSERT_EQ(r.names, (std::vector<std::string>{"a.png", "b.png"}));
  EXPECT_EQ(r.per_image[0].valid_pixels, 6 * 7);
  EXPECT_NEAR(r.per_image[0].abs_rel, 0.0, 1e-6);
  EXPECT_NEAR(r.per_image[1].abs_rel, 4.0 / 20.0, 1e-6);
  EXPECT_NEAR(r.mean.abs_rel, 0.1, 1e-6);
  EXPECT_NEAR(r.mean.rmse, 2.0, 1e-5);
  const nlohmann::json j = DepthEvalResultToJson(r, o);
  EXPECT_EQ(j["images"].get<int>(), 2);
  EXPECT_NEAR(j["abs_rel"].get<double>(), 0.1, 1e-6);
}

TEST(EvalDepth, FolderErrorsNameTheFiles) {
  Folders f("bad");
  DepthEvalOptions o = DepthOnly();
  EXPECT_THROW(EvaluateDepthFolders(f.pred.string(), f.gt.string(), o), Error);  // empty
  const cv::Mat map(4, 4, CV_32F, cv::Scalar(10.0f));
  WriteUint16(f.gt / "000001.png", map);
  WriteUint16(f.gt / "000002.png", map);
  WriteUint16(f.pred / "000001.png", map);
  WriteUint16(f.pred / "000003.png", map);
  try {
    EvaluateDepthFolders(f.pred.string(), f.gt.string(), o);
    FAIL() << "mismatching names accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("000002.png"), std::string::npos) << what;
    EXPECT_NE(what.find("000003.png"), std::string::npos) << what;
  }
  // All GT invalid: clear error, not NaN metrics.
  fs::remove(f.pred / "000003.png");
  fs::remove(f.gt / "000002.png");
  WriteUint16(f.gt / "000001.png", cv::Mat(4, 4, CV_32F, cv::Scalar(0.0f)));
  EXPECT_THROW(EvaluateDepthFolders(f.pred.string(), f.gt.string(), o), Error);
}

TEST(DepthRanges, HandComputedPooledStatisticsPerRange) {
  // (pred, GT): range [0, 10): (1, 2), (4, 4), (12, 6) -> ratios 0.5, 1, 2; range [10, 80): (18, 15),
  // (45, 30) -> 1.2, 1.5; GT 90 m is outside (min_depth, max_depth) = (1e-3, 80).
  const cv::Mat gt = Map(1, 6, {2, 4, 6, 15, 30, 90});
  const cv::Mat pred = Map(1, 6, {1, 4, 12, 18, 45, 10});
  DepthRangeAccumulator acc({0.0, 10.0, 80.0});
  acc.Add(pred, gt, cv::Mat(), DepthOnly());
  const std::vector<DepthRangeStats> r = acc.Ranges();
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].pixels, 3);
  EXPECT_NEAR(r[0].abs_rel, (0.5 + 0.0 + 1.0) / 3.0, 1e-12);
  EXPECT_NEAR(r[0].a1, 1.0 / 3.0, 1e-12);
  EXPECT_NEAR(r[0].median_pred_over_gt, 1.0, 1e-3);
  EXPECT_EQ(r[1].pixels, 2);
  EXPECT_NEAR(r[1].abs_rel, (0.2 + 0.5) / 2.0, 1e-12);
  EXPECT_NEAR(r[1].a1, 0.5, 1e-12);
  EXPECT_NEAR(r[1].median_pred_over_gt, 1.2, 1.2e-3);  // lower median of {1.2, 1.5}
  const DepthRangeStats all = acc.Overall();
  EXPECT_EQ(all.pixels, 5);
  EXPECT_NEAR(all.median_pred_over_gt, 1.2, 1.2e-3);  // 0.5, 1, 1.2, 1.5, 2
  EXPECT_EQ(all.min_depth, 0.0);
  EXPECT_EQ(all.max_depth, 80.0);

  // The image's median-scaling factor multiplies the predictions before the clamp to max_depth.
  DepthRangeAccumulator scaled({0.0, 10.0, 80.0});
  scaled.Add(pred, gt, cv::Mat(), DepthOnly(), 2.0);
  const std::vector<DepthRangeStats> s = scaled.Ranges();
  EXPECT_NEAR(s[0].median_pred_over_gt, 2.0, 2e-3);          // 1, 2, 4
  EXPECT_NEAR(s[1].median_pred_over_gt, 36.0 / 15.0, 3e-3);  // 36 / 15 and 80 (clamped 90) / 30
  EXPECT_NEAR(s[1].abs_rel, (21.0 / 15.0 + 50.0 / 30.0) / 2.0, 1e-12);
  // An empty range reports NaN statistics, not zeros.
  DepthRangeAccumulator far({40.0, 80.0});
  far.Add(pred, gt, cv::Mat(), DepthOnly());
  EXPECT_EQ(far.Overall().pixels, 0);
  EXPECT_TRUE(std::isnan(far.Overall().median_pred_over_gt));
}

TEST(DepthRanges, TextureMaskKeepsOnlyPixelsAtImageEdges) {
  // A vertical step between columns 3 and 4: only those two columns have a Sobel gradient (4 * 200).
  cv::Mat grey(5, 8, CV_8U, cv::Scalar(0));
  grey.colRange(4, 8).setTo(200);
  const cv::Mat mask = TexturedPixelMask(grey, 100.0);
  for (int v = 0; v < 5; ++v) {
    for (int u = 0; u < 8; ++u) EXPECT_EQ(mask.at<uint8_t>(v, u) != 0, u == 3 || u == 4) << u << "," << v;
  }
  EXPECT_EQ(cv::countNonZero(TexturedPixelMask(grey, 801.0)), 0);
  // Masked accumulation: the step's 10 pixels are 2x too far, the others exact.
  const cv::Mat gt(5, 8, CV_32F, cv::Scalar(20.0f));
  cv::Mat pred = gt.clone();
  pred.colRange(3, 5).setTo(40.0f);
  DepthRangeAccumulator textured({0.0, 80.0}), everywhere({0.0, 80.0});
  textured.Add(pred, gt, mask, DepthOnly());
  everywhere.Add(pred, gt, cv::Mat(), DepthOnly());
  EXPECT_EQ(textured.Overall().pixels, 10);
  EXPECT_NEAR(textured.Overall().median_pred_over_gt, 2.0, 2e-3);
  EXPECT_EQ(everywhere.Overall().pixels, 40);
  EXPECT_NEAR(everywhere.Overall().median_pred_over_gt, 1.0, 1e-3);
}

TEST(DepthRanges, InvalidEdgesAndOptionsAreErrors) {
  EXPECT_THROW(DepthRangeAccumulator({5.0}), Error);
  EXPECT_THROW(DepthRangeAccumulator({0.0, 10.0, 10.0}), Error);
  EXPECT_THROW(DepthRangeAccumulator({-1.0, 5.0}), Error);
  DepthEvalOptions o = DepthOnly();
  o.min_image_gradient = 50.0;  // without images
  EXPECT_THROW(o.Check(), Error);
  o.image_dir = "images";  // images without ranges
  EXPECT_THROW(o.Check(), Error);
  o.range_edges = {0.0, 80.0};
  EXPECT_NO_THROW(o.Check());
  o.range_edges = {10.0, 0.0};
  EXPECT_THROW(o.Check(), Error);
}

TEST(EvalDepth, FolderBreakdownByRangeAtTexturedPixels) {
  Folders f("ranges");
  // GT 20 px -> 20 m (fxb 400); a exact, b 25 px -> 16 m (pred / GT 0.8).
  const cv::Mat gt(6, 8, CV_32F, cv::Scalar(20.0f));
  WriteUint16(f.gt / "a.png", gt);
  WriteUint16(f.gt / "b.png", gt);
  WriteUint16(f.pred / "a.png", gt);
  WriteUint16(f.pred / "b.png", cv::Mat(6, 8, CV_32F, cv::Scalar(25.0f)));
  DepthEvalOptions o;
  o.fxb = 400.0;
  o.range_edges = {0.0, 10.0, 80.0};
  DepthEvalResult r = EvaluateDepthFolders(f.pred.string(), f.gt.string(), o);
  ASSERT_EQ(r.ranges.size(), 2u);
  EXPECT_EQ(r.ranges[0].pixels, 0);
  EXPECT_EQ(r.ranges[1].pixels, 2 * 48);
  EXPECT_NEAR(r.ranges[1].abs_rel, 0.1, 1e-6);
  EXPECT_NEAR(r.all_ranges.median_pred_over_gt, 0.8, 1e-3);  // lower median of 48 x 0.8 and 48 x 1
  const nlohmann::json j = DepthEvalResultToJson(r, o);
  EXPECT_EQ(j["ranges"]["per_range"].size(), 2u);
  EXPECT_EQ(j["ranges"]["all"]["pixels"].get<long>(), 96);
  EXPECT_NE(FormatDepthEvalResult(r, o).find("median pred/GT"), std::string::npos);

  // Images: a step in a (columns 3-4 textured), b flat: only a's 12 textured pixels count.
  const fs::path images = f.root / "images";
  fs::create_directories(images);
  cv::Mat step(6, 8, CV_8U, cv::Scalar(0));
  step.colRange(4, 8).setTo(200);
  ASSERT_TRUE(cv::imwrite((images / "a.png").string(), step));
  ASSERT_TRUE(cv::imwrite((images / "b.png").string(), cv::Mat(6, 8, CV_8U, cv::Scalar(90))));
  o.image_dir = images.string();
  o.min_image_gradient = 100.0;
  r = EvaluateDepthFolders(f.pred.string(), f.gt.string(), o);
  EXPECT_EQ(r.all_ranges.pixels, 12);
  EXPECT_NEAR(r.all_ranges.median_pred_over_gt, 1.0, 1e-3);
  EXPECT_NEAR(r.mean.abs_rel, 0.1, 1e-6);  // the main metrics still use every GT pixel

  // An image of another size is an error naming it.
  ASSERT_TRUE(cv::imwrite((images / "b.png").string(), cv::Mat(3, 4, CV_8U, cv::Scalar(90))));
  try {
    EvaluateDepthFolders(f.pred.string(), f.gt.string(), o);
    FAIL() << "an image of another size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("b.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace dvso
