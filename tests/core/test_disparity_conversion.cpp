// DVSO formulas (core/disparity_conversion.h) by hand, the disparity file
// source (names, bilinear resize, errors, NaN handling) and the prediction worker.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <cmath>
#include <filesystem>
#include <limits>

#include "core/disparity_conversion.h"
#include "core/disparity_io.h"
#include "core/disparity_source.h"
#include "core/error.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {

TEST(DisparityConversion, InverseDepthIsDisparityOverFocalTimesBaseline) {
  // d = D / (f_x b): 36 px with f_x = 720, b = 0.5 -> 0.1 1/m (10 m).
  EXPECT_DOUBLE_EQ(InverseDepthFromDisparity(36.0, 720.0, 0.5), 0.1);
  EXPECT_DOUBLE_EQ(InverseDepthFromDisparity(0.0, 720.0, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(InverseDepthFromDisparity(-3.0, 720.0, 0.5), 0.0);
  EXPECT_DOUBLE_EQ(InverseDepthFromDisparity(std::nan(""), 720.0, 0.5), 0.0);
  EXPECT_THROW(InverseDepthFromDisparity(10.0, 720.0, 0.0), Error);
}

TEST(DisparityConversion, VirtualBaselineIsTheTrainingBaselineForEveryCamera) {
  ModelMetadata model;
  model.baseline = 0.54;
  model.fx_over_width = 720.0 / 1240.0;
  EXPECT_NEAR(VirtualBaselineOfModel(model), 0.54, 1e-12);
  // A camera with twice the focal length per width (narrower field of view) sees an object at Z = 20 m
  // as large as the training camera saw it at 10 m: the network perceives Z' = Z (f_t/W_t) / (f_x/W) and
  // answers the training camera's fraction for Z', which in this camera's pixels is f_x b_t / Z.
  const double fx = 1440.0, width = 1240.0, depth = 20.0;
  const double perceived = depth * model.fx_over_width / (fx / width);
  EXPECT_NEAR(perceived, 10.0, 1e-12);
  const double disparity_px = model.fx_over_width * model.baseline / perceived * width;
  EXPECT_NEAR(InverseDepthFromDisparity(disparity_px, fx, VirtualBaselineOfModel(model)), 1.0 / depth, 1e-12);
  EXPECT_THROW(VirtualBaselineOfModel(ModelMetadata{}), Error);
  // Paper "tb": a tuned baseline is used when asked for, for every camera alike.
  model.tuned_baseline = 0.6;
  EXPECT_NEAR(VirtualBaselineOfModel(model, /*tuned=*/true), 0.6, 1e-12);
  EXPECT_NEAR(VirtualBaselineOfModel(model, /*tuned=*/false), 0.54, 1e-12);
}

TEST(DisparityConversion, LeftRightErrorComparesWithTheRightMapAtTheMatch) {
  cv::Mat left(4, 20, CV_32F, cv::Scalar(5.0f));
  cv::Mat right(4, 20, CV_32F, cv::Scalar(5.0f));
  EXPECT_FLOAT_EQ(LeftRightDisparityError(left, right, 10, 1), 0.0f);
  // D^L(10) = 5 -> p' = 5; D^R(5) = 7 -> e_lr = 2.
  right.at<float>(1, 5) = 7.0f;
  EXPECT_FLOAT_EQ(LeftRightDisparityError(left, right, 10, 1), 2.0f);
  // Sub-pixel match: D^L = 4.5 -> p' = 5.5, D^R = (7 + 5) / 2 = 6 -> e_lr = 1.5.
  left.at<float>(1, 10) = 4.5f;
  EXPECT_FLOAT_EQ(LeftRightDisparityError(left, right, 10, 1), 1.5f);
  // Invalid prediction, or the match leaves the image: infinite error (not selected).
  left.at<float>(2, 10) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(std::isinf(LeftRightDisparityError(left, right, 10, 2)));
  EXPECT_TRUE(std::isinf(LeftRightDisparityError(left, right, 3, 0)));  // 3 - 5 < 0
  right.at<float>(3, 5) = 0.0f;
  EXPECT_TRUE(std::isinf(LeftRightDisparityError(left, right, 10, 3)));
  // p' on a pixel centre needs that pixel alone: an invalid neighbour (weight 0) does not matter.
  right.at<float>(0, 6) = 0.0f;
  EXPECT_FLOAT_EQ(LeftRightDisparityError(left, right, 10, 0), 0.0f);
  right.at<float>(0, 5) = 0.0f;
  EXPECT_TRUE(std::isinf(LeftRightDisparityError(left, right, 10, 0)));
}

TEST(DisparityConversion, SanitizeZeroesNaNAndNegatives) {
  cv::Mat m = (cv::Mat_<float>(1, 4) << 2.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
               std::numeric_limits<float>::infinity());
  const cv::Mat s = SanitizeDisparity(m);
  EXPECT_FLOAT_EQ(s.at<float>(0, 0), 2.0f);
  EXPECT_FLOAT_EQ(s.at<float>(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(s.at<float>(0, 2), 0.0f);
  EXPECT_FLOAT_EQ(s.at<float>(0, 3), 0.0f);
}

TEST(DisparityConversion, MetadataJsonRoundTripAndStrictKeys) {
  ModelMetadata m;
  m.input_width = 512;
  m.input_height = 160;
  m.baseline = 0.537;
  m.fx_over_width = 0.579;
  m.config_name = "cpu";
  m.model_kind = "stack";
  m.tuned_baseline = 0.61;
  m.tuned_on = "sim 07";
  const ModelMetadata back = ModelMetadata::FromJson(m.ToJson(), "test");
  EXPECT_EQ(back.input_width, 512);
  EXPECT_EQ(back.input_height, 160);
  EXPECT_DOUBLE_EQ(back.baseline, 0.537);
  EXPECT_DOUBLE_EQ(back.fx_over_width, 0.579);
  EXPECT_EQ(back.config_name, "cpu");
  EXPECT_EQ(back.model_kind, "stack");
  EXPECT_DOUBLE_EQ(back.tuned_baseline, 0.61);
  EXPECT_EQ(back.tuned_on, "sim 07");
  EXPECT_THROW(ModelMetadata::FromJson("{\"basline\": 1}", "test"), Error);
  EXPECT_THROW(ModelMetadata::FromJson("not json", "test"), Error);
  EXPECT_THROW(ModelMetadata::FromJson("{\"baseline\": \"x\"}", "test"), Error);
}

TEST(DisparityResize, BilinearKeepsARampSmoothAndScalesWithWidth) {
  // D(x) = 10 + x on a 40-wide map; resized to 80 wide the values double and
  // stay a ramp: neighbouring pixels differ by the same step (no 2-px stairs).
  cv::Mat ramp(10, 40, CV_32F);
  for (int y = 0; y < ramp.rows; ++y) {
    for (int x = 0; x < ramp.cols; ++x) ramp.at<float>(y, x) = 10.0f + x;
  }
  const cv::Mat big = ResizeDisparity(ramp, 80, 20);
  ASSERT_EQ(big.cols, 80);
  for (int x = 2; x < 76; ++x) {
    EXPECT_NEAR(big.at<float>(5, x + 1) - big.at<float>(5, x), 1.0f, 1e-4) << x;  // 2 * 0.5 px per pixel
  }
  EXPECT_NEAR(big.at<float>(5, 41), 2.0f * (10.0f + (41 + 0.5f) / 2 - 0.5f), 1e-4);
  const cv::Mat nearest = ResizeDisparity(ramp, 80, 20, DisparityResize::kNearest);
  EXPECT_FLOAT_EQ(nearest.at<float>(5, 40), nearest.at<float>(5, 41));  // stairs: fine for sparse labels only
}

TEST(DisparityResize, BilinearNeverMixesInvalidPixels) {
  cv::Mat m(8, 8, CV_32F, cv::Scalar(20.0f));
  m.at<float>(4, 4) = 0.0f;
  const cv::Mat big = ResizeDisparity(m, 16, 16);
  for (int y = 0; y < big.rows; ++y) {
    for (int x = 0; x < big.cols; ++x) {
      const float v = big.at<float>(y, x);
      EXPECT_TRUE(v == 0.0f || std::abs(v - 40.0f) < 1e-4) << x << "," << y << ": " << v;
    }
  }
  EXPECT_EQ(big.at<float>(9, 9), 0.0f);
}

std::string FreshDir(const std::string& name) {
  const std::string dir = dvso::testing::ScratchPath("disp_source_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(FileDisparitySource, ReadsMapsNamedLikeTheImagesAndResizes) {
  const std::string dir = FreshDir("names");
  std::filesystem::create_directories(dir + "/L");
  std::filesystem::create_directories(dir + "/R");
  const cv::Mat map(10, 20, CV_32F, cv::Scalar(4.0f));
  for (const std::string name : {"cam_a", "cam_b"}) {
    WriteKittiMapPng(dir + "/L/" + name + ".png", map);
    WriteKittiMapPng(dir + "/R/" + name + ".png", map * 2);
  }
  FileDisparitySource source(dir + "/L", dir + "/R", {"cam_a", "cam_b"});
  const DisparityPair pair = source.Predict(1, cv::Mat(20, 40, CV_8UC1));
  ASSERT_EQ(pair.left.cols, 40);
  EXPECT_NEAR(pair.left.at<float>(10, 20), 8.0f, 1e-3);   // value scaled with the width
  EXPECT_NEAR(pair.right.at<float>(10, 20), 16.0f, 1e-3);
}

TEST(FileDisparitySource, MissingOrTooFewMapsFailBeforeTheRunNamingTheFile) {
  const std::string dir = FreshDir("missing");
  std::filesystem::create_directories(dir + "/L");
  std::filesystem::create_directories(dir + "/R");
  const cv::Mat map(10, 20, CV_32F, cv::Scalar(4.0f));
  WriteKittiMapPng(dir + "/L/000000.png", map);
  WriteKittiMapPng(dir + "/R/000000.png", map);
  WriteKittiMapPng(dir + "/L/000001.png", map);
  try {
    FileDisparitySource source(dir + "/L", dir + "/R", {"000000", "000001"});
    FAIL() << "missing right map accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dir + "/R/000001.png"), std::string::npos) << e.what();
  }
  // .npy stacks with fewer maps than frames.
  WriteNpyStack(dir + "/l.npy", {cv::Mat(4, 8, CV_32F, cv::Scalar(0.1f))});
  WriteNpyStack(dir + "/r.npy", {cv::Mat(4, 8, CV_32F, cv::Scalar(0.1f))});
  EXPECT_THROW(FileDisparitySource(dir + "/l.npy", dir + "/r.npy", {"a", "b"}), Error);
  FileDisparitySource ok(dir + "/L", dir + "/R", {"000000"});
  EXPECT_NO_THROW(ok.Predict(0, cv::Mat(10, 20, CV_8UC1)));
}

TEST(FileDisparitySource, NpyNaNAndNegativeValuesBecomeInvalid) {
  const std::string dir = FreshDir("npy");
  cv::Mat m(4, 8, CV_32F, cv::Scalar(0.1f));
  m.at<float>(1, 1) = std::numeric_limits<float>::quiet_NaN();
  m.at<float>(2, 2) = -0.1f;
  WriteNpyStack(dir + "/l.npy", {m});
  WriteNpyStack(dir + "/r.npy", {m});
  FileDisparitySource source(dir + "/l.npy", dir + "/r.npy", {"000000"});
  const DisparityPair pair = source.Predict(0, cv::Mat(4, 8, CV_8UC1));
  EXPECT_FLOAT_EQ(pair.left.at<float>(0, 0), 0.8f);  // 0.1 of the width
  EXPECT_FLOAT_EQ(pair.left.at<float>(1, 1), 0.0f);
  EXPECT_FLOAT_EQ(pair.left.at<float>(2, 2), 0.0f);
}

// Returns index-valued maps; fails on a chosen frame.
class CountingSource : public DisparitySource {
 public:
  DisparityPair Predict(int index, const cv::Mat& image) override {
    ++calls;
    if (index == fail_on) throw Error("frame " + std::to_string(index) + " broken");
    cv::Mat m(image.rows, image.cols, CV_32F, cv::Scalar(static_cast<float>(index)));
    return {m, m.clone()};
  }
  std::atomic<int> calls{0};
  int fail_on = -1;
};

TEST(AsyncDisparitySource, ServesPrefetchedFramesComputesOthersAndPassesErrorsBack) {
  auto inner = std::make_unique<CountingSource>();
  CountingSource* counting = inner.get();
  counting->fail_on = 7;
  AsyncDisparitySource async(std::move(inner));
  const cv::Mat image(6, 6, CV_8UC1, cv::Scalar(0));
  async.Prefetch(1, image);
  EXPECT_FLOAT_EQ(async.Predict(1, image).left.at<float>(0, 0), 1.0f);
  async.Prefetch(2, image);  // never asked for: replaced by the next prefetch or ignored
  async.Prefetch(3, image);
  EXPECT_FLOAT_EQ(async.Predict(3, image).left.at<float>(0, 0), 3.0f);
  EXPECT_FLOAT_EQ(async.Predict(5, image).left.at<float>(0, 0), 5.0f);  // not prefetched: computed on demand
  EXPECT_EQ(async.prefetched_used(), 2);
  EXPECT_EQ(async.computed_on_demand(), 1);
  async.Prefetch(7, image);
  EXPECT_THROW(async.Predict(7, image), Error);
  EXPECT_FLOAT_EQ(async.Predict(8, image).left.at<float>(0, 0), 8.0f);  // the worker survives an error
}

// Frame 1 is being computed and frame 2 is queued when frame 1 is asked for: frame 1's result must
// reach the caller (the worker must not compute frame 2 over it before the caller wakes) and frame 2
// is still served from its prefetch afterwards.
class GatedSource : public DisparitySource {
 public:
  DisparityPair Predict(int index, const cv::Mat& image) override {
    if (index == 1) {
      std::unique_lock<std::mutex> lock(mutex);
      started = true;
      changed.notify_all();
      changed.wait(lock, [&] { return released; });
    }
    ++calls;
    cv::Mat m(image.rows, image.cols, CV_32F, cv::Scalar(static_cast<float>(index)));
    return {m, m.clone()};
  }
  std::mutex mutex;
  std::condition_variable changed;
  bool started = false, released = false;
  std::atomic<int> calls{0};
};

TEST(AsyncDisparitySource, QueuedPrefetchDoesNotOverwriteTheResultBeingWaitedFor) {
  auto inner = std::make_unique<GatedSource>();
  GatedSource* gated = inner.get();
  AsyncDisparitySource async(std::move(inner));
  const cv::Mat image(4, 4, CV_8UC1, cv::Scalar(0));
  async.Prefetch(1, image);
  {
    std::unique_lock<std::mutex> lock(gated->mutex);
    gated->changed.wait(lock, [&] { return gated->started; });  // frame 1 is running
  }
  async.Prefetch(2, image);  // queued behind it
  std::thread release([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    std::lock_guard<std::mutex> lock(gated->mutex);
    gated->released = true;
    gated->changed.notify_all();
  });
  EXPECT_FLOAT_EQ(async.Predict(1, image).left.at<float>(0, 0), 1.0f);
  release.join();
  EXPECT_FLOAT_EQ(async.Predict(2, image).left.at<float>(0, 0), 2.0f);
  EXPECT_EQ(async.prefetched_used(), 2);
  EXPECT_EQ(async.computed_on_demand(), 0);
  EXPECT_EQ(gated->calls.load(), 2);
}

}  // namespace
}  // namespace dvso
