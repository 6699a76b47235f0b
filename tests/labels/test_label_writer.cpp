// LabelWriter driven by hand-made odometry events: labels appear only once
// the keyframes are final, use the final poses, and every frame gets a file.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/disparity_io.h"
#include "core/fs_util.h"
#include "sdso_labels/label_writer.h"

using namespace dvso;
using namespace dvso::labels;
namespace fs = std::filesystem;

namespace {

StereoCamera Camera() {
  StereoCamera c;
  c.left = PinholeCamera{100, 100, 20, 10, 41, 21};
  c.baseline = 0.5;
  return c;
}

std::string TempDir() {
  const fs::path dir = fs::temp_directory_path() / ("dvso_labelwriter_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  return dir.string();
}

vo::PointInfo Point(int host, float u, float v, double idepth, int good) {
  vo::PointInfo p;
  p.host_frame_index = host;
  p.u = u;
  p.v = v;
  p.idepth = idepth;
  p.num_good_residuals = good;
  p.idepth_hessian = 1e6f;  // well constrained (sigma_disp = fxB / 1000)
  return p;
}

Eigen::Isometry3d Forward(double z) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().z() = z;
  return T;
}

}  // namespace

TEST(LabelWriter, WritesWhenKeyframesAreFinalWithFinalPoses) {
  const std::string out = TempDir();
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 0;  // only the window at tracking time (later keyframes: next test)
  LabelWriter writer(Camera(), options, out, [&](int i, const cv::Mat& m) { seen[i] = m.clone(); });

  // Frame 0: keyframe, window = {0}.
  vo::WindowEvent w0;
  w0.keyframes.push_back({0, Eigen::Isometry3d::Identity(), 0, 0});
  writer.OnWindowOptimized(w0);
  vo::FrameEvent f0;
  f0.frame_index = 0;
  f0.status = vo::FrameStatus::kKeyframe;
  f0.reference_frame_index = 0;
  writer.OnFrameTracked(f0);
  // Frame 1: tracked 1 m ahead of keyframe 0.
  vo::FrameEvent f1 = f0;
  f1.frame_index = 1;
  f1.status = vo::FrameStatus::kTracked;
  f1.T_ref_frame = Forward(1.0);
  writer.OnFrameTracked(f1);
  EXPECT_EQ(writer.frames_written(), 0);  // keyframe 0 is not final yet
  EXPECT_FALSE(fs::exists(out + "/000000.png"));

  // Keyframe 0 leaves with two points: one well constrained at the image centre, 10 m away,
  // one with a single good residual (dropped by min_good_residuals = 2).
  writer.OnPointsMarginalized({Point(0, 20, 10, 0.1, 3), Point(0, 30, 10, 0.2, 1)});
  // Its final pose moved 0.5 m backwards compared to what tracking thought.
  writer.OnKeyframeMarginalized({0, Forward(-0.5), 0, 0});
  EXPECT_EQ(writer.frames_written(), 2);
  ASSERT_TRUE(seen.count(0) && seen.count(1));
  // Keyframe: its own point at its own pixel, disparity fxB * idepth.
  EXPECT_FLOAT_EQ(seen[0].at<float>(10, 20), 100 * 0.5 * 0.1f);
  EXPECT_EQ(cv::countNonZero(seen[0]), 1);
  // Frame 1 sits 1 m ahead of the FINAL keyframe pose: the point is 9 m away.
  EXPECT_NEAR(seen[1].at<float>(10, 20), 100 * 0.5 / 9.0, 1e-5);
  EXPECT_NEAR(ReadKittiMapPng(out + "/000001.png").at<float>(10, 20), 100 * 0.5 / 9.0, 0.5 / 256);

  // A lost frame has no labels but still gets a file, in order.
  vo::FrameEvent lost;
  lost.frame_index = 2;
  lost.status = vo::FrameStatus::kLost;
  writer.OnFrameTracked(lost);
  writer.OnFinished();
  EXPECT_EQ(writer.frames_written(), 3);
  EXPECT_EQ(cv::countNonZero(ReadKittiMapPng(out + "/000002.png")), 0);
  EXPECT_EQ(writer.frames_pending(), 0);
}

TEST(LabelWriter, ResumeKeepsExistingFiles) {
  const std::string out = TempDir() + "_resume";
  fs::create_directories(out);
  cv::Mat existing(21, 41, CV_32F, cv::Scalar(0));
  existing.at<float>(1, 1) = 42.f;
  WriteKittiMapPng(out + "/000000.png", existing);
  LabelWriter writer(Camera(), LabelOptions(), out);
  vo::FrameEvent lost;
  lost.frame_index = 0;
  lost.status = vo::FrameStatus::kLost;
  writer.OnFrameTracked(lost);
  writer.OnFinished();
  EXPECT_FLOAT_EQ(ReadKittiMapPng(out + "/000000.png").at<float>(1, 1), 42.f);
}

TEST(LabelWriter, LaterKeyframesAlsoLabelEarlierFrames) {
  const std::string out = TempDir() + "_future";
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 1;
  LabelWriter writer(Camera(), options, out, [&](int i, const cv::Mat& m) { seen[i] = m.clone(); });
  vo::WindowEvent w0;
  w0.frame_index = 0;
  w0.keyframes.push_back({0, Eigen::Isometry3d::Identity(), 0, 0});
  writer.OnWindowOptimized(w0);
  vo::FrameEvent f0;
  f0.frame_index = 0;
  f0.status = vo::FrameStatus::kKeyframe;
  f0.reference_frame_index = 0;
  writer.OnFrameTracked(f0);
  // Keyframe 0 leaves without points: frame 0 must still wait for one later keyframe.
  writer.OnPointsMarginalized({});
  writer.OnKeyframeMarginalized({0, Eigen::Isometry3d::Identity(), 0, 0});
  EXPECT_EQ(writer.frames_written(), 0);
  // Keyframe 1, 2 m ahead, hosts a point 10 m in front of it (12 m from frame 0).
  vo::WindowEvent w1;
  w1.frame_index = 1;
  w1.keyframes.push_back({1, Forward(2.0), 0, 0});
  writer.OnWindowOptimized(w1);
  vo::FrameEvent f1 = f0;
  f1.frame_index = 1;
  f1.reference_frame_index = 1;
  writer.OnFrameTracked(f1);
  writer.OnPointsMarginalized({Point(1, 20, 10, 0.1, 3)});
  writer.OnKeyframeMarginalized({1, Forward(2.0), 0, 0});
  writer.OnFinished();
  ASSERT_TRUE(seen.count(0) && seen.count(1));
  EXPECT_NEAR(seen[0].at<float>(10, 20), 100 * 0.5 / 12.0, 1e-5);
  EXPECT_FLOAT_EQ(seen[1].at<float>(10, 20), 100 * 0.5 * 0.1f);
}
