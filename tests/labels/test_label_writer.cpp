// LabelWriter driven by hand-made odometry events: labels appear only once
// the keyframes are final, use the final poses, and every frame gets a file.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <random>
#include <thread>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "sdso_labels/label_writer.h"
#include "tests/temp_dir.h"
#include "tests/vo/test_backend_util.h"
#include "vo/optimization/residuals.h"
#include "vo/optimization/window.h"

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
  return dvso::testing::ScratchPath("labelwriter");
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

// A frame tracked against keyframe `reference` (a keyframe itself when frame == reference).
vo::FrameEvent Tracked(int frame, int reference, const Eigen::Isometry3d& T_ref_frame = Eigen::Isometry3d::Identity()) {
  vo::FrameEvent e;
  e.frame_index = frame;
  e.status = frame == reference ? vo::FrameStatus::kKeyframe : vo::FrameStatus::kTracked;
  e.reference_frame_index = reference;
  e.T_ref_frame = T_ref_frame;
  return e;
}

vo::FrameEvent Lost(int frame) {
  vo::FrameEvent e;
  e.frame_index = frame;
  e.status = vo::FrameStatus::kLost;
  return e;
}

// The window after keyframe `newest` was added: keyframes (id, pose), oldest first.
vo::WindowEvent Window(int newest, const std::vector<std::pair<int, Eigen::Isometry3d>>& keyframes) {
  vo::WindowEvent w;
  w.frame_index = newest;
  for (const auto& [id, pose] : keyframes) w.keyframes.push_back({id, pose, 0, 0});
  return w;
}

// Keyframe `id` leaves the window with its points and final pose.
void Marginalize(LabelWriter* writer, int id, const Eigen::Isometry3d& pose, const std::vector<vo::PointInfo>& points) {
  writer->OnPointsMarginalized(points);
  writer->OnKeyframeMarginalized({id, pose, 0, 0});
}

// Every map the writer produces, by frame index.
LabelSink Collect(std::map<int, cv::Mat>* maps) {
  return [maps](int i, const cv::Mat& m) { (*maps)[i] = m.clone(); };
}

// Frame 0 becomes keyframe 0, alone in the window (how most tests below start).
void StartAtKeyframeZero(LabelWriter* writer) {
  writer->OnWindowOptimized(Window(0, {{0, Eigen::Isometry3d::Identity()}}));
  writer->OnFrameTracked(Tracked(0, 0));
}

}  // namespace

TEST(LabelWriter, WritesWhenKeyframesAreFinalWithFinalPoses) {
  const std::string out = TempDir();
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 0;  // only the window at tracking time (later keyframes: next test)
  LabelWriter writer(Camera(), options, out, Collect(&seen));

  // Frame 0: keyframe, window = {0}; frame 1 tracked 1 m ahead of it.
  StartAtKeyframeZero(&writer);
  writer.OnFrameTracked(Tracked(1, 0, Forward(1.0)));
  EXPECT_EQ(writer.frames_written(), 0);  // keyframe 0 is not final yet
  EXPECT_FALSE(fs::exists(out + "/000000.png"));

  // Keyframe 0 leaves with two points: one well constrained at the image centre, 10 m away,
  // one with a single good residual (dropped by min_good_residuals = 2).
  // Its final pose moved 0.5 m backwards compared to what tracking thought.
  Marginalize(&writer, 0, Forward(-0.5), {Point(0, 20, 10, 0.1, 3), Point(0, 30, 10, 0.2, 1)});
  EXPECT_EQ(writer.frames_written(), 2);
  ASSERT_TRUE(seen.count(0) && seen.count(1));
  // Keyframe: its own point at its own pixel, disparity fxB * idepth.
  EXPECT_FLOAT_EQ(seen[0].at<float>(10, 20), 100 * 0.5 * 0.1f);
  EXPECT_EQ(cv::countNonZero(seen[0]), 1);
  // Frame 1 sits 1 m ahead of the FINAL keyframe pose: the point is 9 m away.
  EXPECT_NEAR(seen[1].at<float>(10, 20), 100 * 0.5 / 9.0, 1e-5);
  EXPECT_NEAR(ReadKittiMapPng(out + "/000001.png").at<float>(10, 20), 100 * 0.5 / 9.0, 0.5 / 256);

  // A lost frame has no labels but still gets a file, in order.
  writer.OnFrameTracked(Lost(2));
  writer.OnFinished();
  EXPECT_EQ(writer.frames_written(), 3);
  EXPECT_EQ(cv::countNonZero(ReadKittiMapPng(out + "/000002.png")), 0);
  EXPECT_EQ(writer.frames_pending(), 0);
}

TEST(LabelWriter, KeyframeCandidatesLabelOnlyTheirOwnKeyframe) {
  for (const bool enabled : {false, true}) {
    const std::string out = TempDir() + (enabled ? "_candidates_on" : "_candidates_off");
    std::map<int, cv::Mat> seen;
    LabelOptions options;
    options.future_keyframes = 0;
    options.keyframe_candidates = enabled;
    LabelWriter writer(Camera(), options, out, Collect(&seen));
    StartAtKeyframeZero(&writer);
    // Keyframe 0's stereo-matched candidates: one 2 m away (never activated: it would leave the
    // view), one 100 m away (beyond max_depth: not a label).
    writer.OnKeyframeCandidates(0, {Point(0, 5, 5, 0.5, 0), Point(0, 35, 15, 0.01, 0)});
    writer.OnFrameTracked(Tracked(1, 0, Forward(1.0)));
    // The keyframe's final pose differs from the tracked one: the candidate still lands on its pixel.
    Marginalize(&writer, 0, Forward(-0.5), {Point(0, 20, 10, 0.1, 3)});
    writer.OnFinished();
    ASSERT_TRUE(seen.count(0) && seen.count(1));
    EXPECT_FLOAT_EQ(seen[0].at<float>(10, 20), 100 * 0.5 * 0.1f);  // the active point, as always
    if (enabled) {
      EXPECT_NEAR(seen[0].at<float>(5, 5), 100 * 0.5 * 0.5, 1e-4);  // disparity fxB * idepth
      EXPECT_EQ(cv::countNonZero(seen[0]), 2);
    } else {
      EXPECT_EQ(cv::countNonZero(seen[0]), 1);
    }
    // Frame 1 (not a keyframe) gets only the active point: a candidate labels its keyframe alone.
    EXPECT_EQ(cv::countNonZero(seen[1]), 1);
  }
}

// A candidate that DSO activates becomes an active point at the same host pixel: it labels only through
// that point and its filters, never a second time as an unfiltered candidate.
TEST(LabelWriter, ActivatedKeyframeCandidateIsNotLabelledAgainAsACandidate) {
  const std::string out = TempDir() + "_activated";
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 0;
  options.keyframe_candidates = true;
  LabelWriter writer(Camera(), options, out, Collect(&seen));
  StartAtKeyframeZero(&writer);
  writer.OnKeyframeCandidates(0, {Point(0, 20, 10, 0.1, 0), Point(0, 5, 5, 0.5, 0)});
  // The next window optimisation has the first candidate as an active point of keyframe 0.
  vo::WindowEvent window = Window(1, {{0, Eigen::Isometry3d::Identity()}, {1, Forward(1.0)}});
  window.points.push_back(Point(0, 20, 10, 0.1, 3));
  writer.OnWindowOptimized(window);
  // It leaves with a single good residual: min_good_residuals drops it, so no label may be left there.
  Marginalize(&writer, 0, Eigen::Isometry3d::Identity(), {Point(0, 20, 10, 0.1, 1)});
  writer.OnFinished();
  ASSERT_TRUE(seen.count(0));
  EXPECT_EQ(seen[0].at<float>(10, 20), 0.0f);
  EXPECT_NEAR(seen[0].at<float>(5, 5), 100 * 0.5 * 0.5, 1e-4);  // the never-activated candidate stays
}

TEST(LabelWriter, StereoEnergyFarAboveTheKeyframesMedianIsNotALabel) {
  // Keyframe 0's points, marginalised in two batches (points leaving the view early, then the
  // rest with the keyframe): five with static stereo energies 100-140 and one at 400 (a pattern
  // straddling a silhouette matches worse on the pair: a wrong label in the label worlds); the
  // median of the six (upper middle) is 130. One point has no stereo residual.
  auto with_energy = [](int u, float stereo_energy) {
    vo::PointInfo p = Point(0, static_cast<float>(u), 10, 0.1, 3);
    p.stereo_energy = stereo_energy;
    return p;
  };
  const double ratios[] = {1e9, 1.5, 3.5};
  for (int r = 0; r < 3; ++r) {
    const double ratio = ratios[r];
    const std::string out = TempDir() + "_stereo_ratio_" + std::to_string(r);
    std::map<int, cv::Mat> seen;
    LabelOptions options;
    options.future_keyframes = 0;
    options.max_stereo_energy_ratio = ratio;
    LabelWriter writer(Camera(), options, out, Collect(&seen));
    StartAtKeyframeZero(&writer);
    writer.OnPointsMarginalized({with_energy(4, 100.f), with_energy(8, 400.f), with_energy(12, 110.f)});
    Marginalize(&writer, 0, Eigen::Isometry3d::Identity(),
                {with_energy(16, 120.f), with_energy(20, 130.f), with_energy(24, 140.f), with_energy(28, -1.f)});
    writer.OnFinished();
    ASSERT_TRUE(seen.count(0));
    // 1.5 x 130 = 195: only the point at 400 goes; 3.5 x 130 = 455 and "off" keep it.
    EXPECT_EQ(seen[0].at<float>(10, 8) > 0.f, ratio > 3.4) << ratio;
    for (const int u : {4, 12, 16, 20, 24, 28}) EXPECT_GT(seen[0].at<float>(10, u), 0.f) << ratio << " u=" << u;
  }
  LabelOptions bad;
  bad.max_stereo_energy_ratio = 0;
  EXPECT_THROW(bad.Check(), Error);

  // On noise-free images every energy is small: the floor keeps 1.5 x median from dropping
  // points for interpolation errors (energies 1-4, one at 20, floor 32: all kept).
  const std::string clean_out = TempDir() + "_stereo_ratio_floor";
  std::map<int, cv::Mat> clean;
  LabelOptions options;
  options.future_keyframes = 0;
  LabelWriter writer(Camera(), options, clean_out, Collect(&clean));
  StartAtKeyframeZero(&writer);
  Marginalize(&writer, 0, Eigen::Isometry3d::Identity(),
              {with_energy(4, 1.f), with_energy(8, 20.f), with_energy(12, 2.f), with_energy(16, 3.f), with_energy(20, 4.f)});
  writer.OnFinished();
  ASSERT_TRUE(clean.count(0));
  EXPECT_EQ(cv::countNonZero(clean[0]), 5);
}

TEST(LabelWriter, SilhouettePointOnTheBackgroundPixelIsDroppedByItsStereoEnergy) {
  // A constructed stereo pair (320x240, fx 300, baseline 0.5 m, sensor noise 1.5 grey levels):
  // a textured foreground at 5 m (disparity 30 px) covers the pixels x <= 159, a textured
  // background at 20 m (7.5 px) the rest; in the right image the foreground hides the background.
  // Right labels: points inside either surface at its depth. The known wrong label (the main one
  // of the label worlds, docs/labels.md): a point on the first background pixel, x = 160, whose
  // pattern straddles the silhouette and which carries the foreground's depth. Its static stereo
  // energy, evaluated by the odometry's own residual, must lift it above 1.5x the keyframe median.
  const StereoCamera camera{vo::testing::SmallCamera(), 0.5};
  const double kEdge = 159.5, kForegroundDepth = 5.0, kBackgroundDepth = 20.0;
  const double d_fg = camera.left.fx * camera.baseline / kForegroundDepth;
  const double d_bg = camera.left.fx * camera.baseline / kBackgroundDepth;
  auto foreground = [](double x, double y) { return 120 + 45 * std::sin(x / 6.0 + y / 11.0) + 20 * std::sin(y / 5.0); };
  auto background = [](double x, double y) { return 110 + 50 * std::sin(x / 8.0 - y / 13.0) + 25 * std::cos(x / 4.0); };
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.5);
  cv::Mat left(camera.left.height, camera.left.width, CV_32F), right(left.size(), CV_32F);
  for (int y = 0; y < left.rows; ++y) {
    for (int x = 0; x < left.cols; ++x) {
      left.at<float>(y, x) = static_cast<float>((x < kEdge ? foreground(x, y) : background(x, y)) + noise(rng));
      const bool foreground_visible = x + d_fg < kEdge;  // scene point x_left = x_right + d
      right.at<float>(y, x) = static_cast<float>(
          (foreground_visible ? foreground(x + d_fg, y) : background(x + d_bg, y)) + noise(rng));
    }
  }
  vo::WindowOptions window_options;
  vo::Window window(window_options, camera);
  vo::KeyframeInput keyframe;
  keyframe.id = 0;
  keyframe.left = vo::testing::MakePyramid(left, camera.left);
  keyframe.right = vo::testing::MakePyramid(right, camera.left);
  window.AddKeyframe(keyframe);
  struct Candidate {
    float u, v;
    double depth;
    bool right_label;
  };
  std::vector<Candidate> candidates;
  for (int i = 0; i < 12; ++i) {
    const float v = 30.0f + 15.0f * i;
    candidates.push_back({60.0f + 7 * i, v, kForegroundDepth, true});
    candidates.push_back({200.0f + 8 * i, v + 5, kBackgroundDepth, true});
  }
  const Candidate silhouette{160.0f, 121.0f, kForegroundDepth, false};
  candidates.push_back(silhouette);
  const vo::ResidualGeometry geometry = vo::StaticStereoGeometry(window.keyframe(0), camera, window_options);
  std::vector<vo::PointInfo> points;
  for (const Candidate& c : candidates) {
    const int id = window.AddPoint(0, c.u, c.v, 1.0 / c.depth);
    ASSERT_GE(id, 0);
    vo::ResidualEvaluation evaluation;
    vo::EvaluateResidual(geometry, window.keyframe(0).points.back(), 1.0 / c.depth, window_options, false, &evaluation);
    ASSERT_NE(evaluation.state, vo::ResidualState::kOutOfBounds);
    vo::PointInfo p = Point(0, c.u, c.v, 1.0 / c.depth, 3);
    p.stereo_energy = evaluation.energy;
    points.push_back(p);
  }
  for (const double ratio : {1e9, 1.5}) {
    const std::string out = TempDir() + "_silhouette_" + (ratio < 100 ? "on" : "off");
    std::map<int, cv::Mat> seen;
    LabelOptions options;
    options.future_keyframes = 0;
    options.max_stereo_energy_ratio = ratio;
    LabelWriter writer(camera, options, out, Collect(&seen));
    StartAtKeyframeZero(&writer);
    Marginalize(&writer, 0, Eigen::Isometry3d::Identity(), points);
    writer.OnFinished();
    ASSERT_TRUE(seen.count(0));
    int right_kept = 0, right_total = 0;
    for (const Candidate& c : candidates) {
      const float label = seen[0].at<float>(static_cast<int>(c.v), static_cast<int>(c.u));
      if (!c.right_label) {
        // Without the filter the wrong label is there: 30 px where the GT says 7.5 px.
        EXPECT_EQ(label > 0.f, ratio > 100) << "silhouette label " << label << " ratio " << ratio;
        if (label > 0.f) {
          EXPECT_NEAR(label, d_fg, 1e-3);
        }
        continue;
      }
      ++right_total;
      if (label > 0.f) ++right_kept;
    }
    // Sensor noise spreads the right points' energies around the median too (a sum over the 8
    // pattern pixels: here 6 to 46 around a median of 22, the silhouette point 7300), so the
    // filter also drops some right labels (here 5 of 24 with libstdc++'s noise; 13-20 % of the labels in
    // the label worlds). The silhouette point's energy is above the outlier threshold: in the odometry
    // its residual is rejected, and the labels see it through Point::rejected_stereo_energy.
    if (ratio > 100) {
      EXPECT_EQ(right_kept, right_total);
    }
    EXPECT_GE(right_kept, 0.6 * right_total) << ratio;
  }
}

TEST(LabelWriter, ResumeKeepsExistingFiles) {
  const std::string out = TempDir() + "_resume";
  fs::create_directories(out);
  cv::Mat existing(21, 41, CV_32F, cv::Scalar(0));
  existing.at<float>(1, 1) = 42.f;
  WriteKittiMapPng(out + "/000000.png", existing);
  LabelWriter writer(Camera(), LabelOptions(), out);
  writer.OnFrameTracked(Lost(0));
  writer.OnFinished();
  EXPECT_FLOAT_EQ(ReadKittiMapPng(out + "/000000.png").at<float>(1, 1), 42.f);
}

TEST(LabelWriter, LaterKeyframesAlsoLabelEarlierFrames) {
  const std::string out = TempDir() + "_future";
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 1;
  LabelWriter writer(Camera(), options, out, Collect(&seen));
  StartAtKeyframeZero(&writer);
  // Keyframe 0 leaves without points: frame 0 must still wait for one later keyframe.
  Marginalize(&writer, 0, Eigen::Isometry3d::Identity(), {});
  EXPECT_EQ(writer.frames_written(), 0);
  // Keyframe 1, 2 m ahead, hosts a point 10 m in front of it (12 m from frame 0).
  writer.OnWindowOptimized(Window(1, {{1, Forward(2.0)}}));
  writer.OnFrameTracked(Tracked(1, 1));
  Marginalize(&writer, 1, Forward(2.0), {Point(1, 20, 10, 0.1, 3)});
  writer.OnFinished();
  ASSERT_TRUE(seen.count(0) && seen.count(1));
  EXPECT_NEAR(seen[0].at<float>(10, 20), 100 * 0.5 / 12.0, 1e-5);
  EXPECT_FLOAT_EQ(seen[1].at<float>(10, 20), 100 * 0.5 * 0.1f);
}

TEST(LabelWriter, PastKeyframesLabelLaterFramesAndMemoryStaysBounded) {
  const std::string out = TempDir() + "_past";
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 0;
  options.past_keyframes = 2;
  LabelWriter writer(Camera(), options, out, Collect(&seen));
  // A sliding window of one keyframe per frame, moving 0.1 m per frame; keyframe k
  // hosts one point 10 m ahead of it on the optical axis.
  const int frames = 30;
  int max_hosts = 0;
  for (int k = 0; k < frames; ++k) {
    writer.OnWindowOptimized(Window(k, {{k, Forward(0.1 * k)}}));
    writer.OnFrameTracked(Tracked(k, k));
    Marginalize(&writer, k, Forward(0.1 * k), {Point(k, 20, 10, 0.1, 3)});
    max_hosts = std::max(max_hosts, writer.hosts_held());
  }
  writer.OnFinished();
  ASSERT_EQ(static_cast<int>(seen.size()), frames);
  // Frame 5 sees its own point (10 m) and those of keyframes 3 and 4 (9.8 m, 9.9 m), all
  // on the optical axis: the nearest wins the pixel, the others are occluded.
  EXPECT_NEAR(seen[5].at<float>(10, 20), 100 * 0.5 / 9.8, 1e-4);
  EXPECT_EQ(cv::countNonZero(seen[5]), 1);
  // Frame 0 has no past keyframes: only its own point.
  EXPECT_FLOAT_EQ(seen[0].at<float>(10, 20), 100 * 0.5 * 0.1f);
  // Held: the past keyframes and the one being written, independent of the sequence length.
  EXPECT_LE(max_hosts, options.past_keyframes + 2);
  EXPECT_EQ(writer.hosts_held(), 0);
  EXPECT_EQ(writer.frames_pending(), 0);
  EXPECT_GT(writer.counters().projected, 0);
  EXPECT_EQ(writer.counters().frames, frames);
}

TEST(LabelWriter, ResetDropsOldMapKeyframes) {
  const std::string out = TempDir() + "_reset";
  std::map<int, cv::Mat> seen;
  LabelOptions options;
  options.future_keyframes = 3;
  options.past_keyframes = 3;
  LabelWriter writer(Camera(), options, out, Collect(&seen));
  StartAtKeyframeZero(&writer);
  Marginalize(&writer, 0, Eigen::Isometry3d::Identity(), {Point(0, 20, 10, 0.1, 3)});
  writer.OnReset(1);
  // The new map's keyframe 2 sits at the same world origin but must not label frame 0,
  // and keyframe 0 (old map) must not label frame 2.
  writer.OnFrameTracked(Lost(1));
  writer.OnWindowOptimized(Window(2, {{2, Eigen::Isometry3d::Identity()}}));
  writer.OnFrameTracked(Tracked(2, 2));
  Marginalize(&writer, 2, Eigen::Isometry3d::Identity(), {Point(2, 30, 10, 0.2, 3)});
  writer.OnFinished();
  ASSERT_EQ(seen.size(), 3u);
  EXPECT_EQ(cv::countNonZero(seen[0]), 1);
  EXPECT_GT(seen[0].at<float>(10, 20), 0.f);
  EXPECT_EQ(cv::countNonZero(seen[1]), 0);
  EXPECT_EQ(cv::countNonZero(seen[2]), 1);
  EXPECT_GT(seen[2].at<float>(10, 30), 0.f);
  EXPECT_EQ(writer.hosts_held(), 0);
}

TEST(LabelWriter, WorkerThreadWritesTheSameMaps) {
  // The sliding-window scenario above, produced on the calling thread and on a worker.
  std::map<int, cv::Mat> maps[2];
  for (int threaded = 0; threaded < 2; ++threaded) {
    LabelOptions options;
    options.future_keyframes = 2;
    options.past_keyframes = 2;
    LabelWriter writer(Camera(), options, TempDir() + "_worker" + std::to_string(threaded),
                       [&](int i, const cv::Mat& m) { maps[threaded][i] = m.clone(); }, {}, threaded == 1);
    for (int k = 0; k < 20; ++k) {
      writer.OnWindowOptimized(Window(k, {{k, Forward(0.1 * k)}}));
      writer.OnFrameTracked(Tracked(k, k));
      Marginalize(&writer, k, Forward(0.1 * k), {Point(k, 20 + k % 3, 10, 0.1, 3)});
    }
    writer.OnFinished();
    EXPECT_EQ(writer.frames_written(), 20);
    EXPECT_EQ(writer.counters().frames, 20);
  }
  ASSERT_EQ(maps[0].size(), 20u);
  ASSERT_EQ(maps[1].size(), 20u);
  for (int i = 0; i < 20; ++i) {
    EXPECT_EQ(cv::countNonZero(maps[0][i] != maps[1][i]), 0) << "frame " << i;
    EXPECT_GT(cv::countNonZero(maps[0][i]), 0) << "frame " << i;
  }
}

TEST(LabelProducer, WorkerErrorsReachTheCaller) {
  LabelProducerOptions options;
  options.worker_thread = true;
  options.max_queue = 1;
  LabelProducer producer(Camera(), options, TempDir() + "_error", {},
                         [](int frame, cv::Mat* left, cv::Mat* right) {
                           if (frame == 2) throw Error("cannot read frame 2");
                           *left = cv::Mat(21, 41, CV_8U, cv::Scalar(0));
                           *right = left->clone();
                         });
  bool thrown = false;
  try {
    for (int i = 0; i < 6; ++i) {
      LabelJob job;
      job.frame_index = i;
      job.has_pose = true;
      job.points.push_back({Eigen::Vector3d(0, 0, 10)});
      producer.Submit(std::move(job));
    }
    producer.Finish();
  } catch (const Error& e) {
    thrown = true;
    EXPECT_NE(std::string(e.what()).find("frame 2"), std::string::npos);
  }
  EXPECT_TRUE(thrown);
  EXPECT_LT(producer.frames_written(), 6);
}

// The time the image loader takes (a pair decoded again) is image-read time, counted by the reader: the
// label time excludes it, so the run summary does not subtract it twice.
TEST(LabelProducer, LabelTimeExcludesTheImageLoader) {
  constexpr int kFrames = 4;
  constexpr auto kLoad = std::chrono::milliseconds(40);
  LabelProducer producer(Camera(), LabelProducerOptions{}, TempDir() + "_timing", {},
                         [&](int, cv::Mat* left, cv::Mat* right) {
                           std::this_thread::sleep_for(kLoad);
                           *left = cv::Mat(21, 41, CV_8U, cv::Scalar(0));
                           *right = left->clone();
                         });
  for (int i = 0; i < kFrames; ++i) {
    LabelJob job;
    job.frame_index = i;
    job.has_pose = true;
    job.points.push_back({Eigen::Vector3d(0, 0, 10)});
    producer.Submit(std::move(job));
  }
  producer.Finish();
  EXPECT_EQ(producer.frames_written(), kFrames);
  const double load_ms = std::chrono::duration<double, std::milli>(kLoad).count();
  EXPECT_LT(producer.counters().extract_ms, 0.5 * kFrames * load_ms);
}

TEST(LabelProducer, RightLabelsSeeThePointsFromTheRightCamera) {
  const std::string out = TempDir() + "_right";
  std::map<int, cv::Mat> left_maps, right_maps;
  LabelProducerOptions options;
  options.right_labels = true;
  LabelProducer producer(Camera(), options, out, Collect(&left_maps), {},
                         Collect(&right_maps));
  LabelJob job;
  job.frame_index = 3;
  job.has_pose = true;
  job.points.push_back({Eigen::Vector3d(0, 0, 10)});  // disparity fxB/z = 100 * 0.5 / 10 = 5 px
  producer.Submit(std::move(job));
  producer.Finish();
  ASSERT_TRUE(left_maps.count(3) && right_maps.count(3));
  EXPECT_FLOAT_EQ(left_maps[3].at<float>(10, 20), 5.f);
  EXPECT_FLOAT_EQ(right_maps[3].at<float>(10, 15), 5.f);  // x_right = x_left - disparity
  EXPECT_EQ(cv::countNonZero(right_maps[3]), 1);
  EXPECT_TRUE(fs::exists(LabelProducer::LabelPath(out, 3, true)));
  EXPECT_EQ(LabelProducer::LabelPath(out, 3, true), out + "/right/000003.png");
  EXPECT_FLOAT_EQ(ReadKittiMapPng(out + "/right/000003.png").at<float>(10, 15), 5.f);
  EXPECT_EQ(producer.counters().right_verified, 1);
}
