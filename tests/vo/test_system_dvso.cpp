// DVSO mode (paper section 4) of the System: mode capabilities, depth
// initialisation from D^L ("in"), the left-right check ("lr"), and end-to-end
// runs with the simulator's exact disparities as predictions: metric without
// alignment, the trajectory scale following the predictions' scale, and bad
// predictions (NaN, zero, negative) never crashing or producing NaN poses.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "core/disparity_conversion.h"
#include "core/error.h"
#include "core/trajectory.h"
#include "tests/dvso_cli_runner.h"
#include "tests/vo/simulated_sequence.h"
#include "vo/system/output_writers.h"
#include "vo/system/system.h"

namespace dvso::vo {
namespace {

constexpr int kFrames = 40;

const testing::SimulatedSequence& Sequence() { return testing::SimulatedKitti00(kFrames); }

// Serves the simulator's exact disparities, optionally scaled or damaged.
class OracleSource : public DisparitySource {
 public:
  DisparityPair Predict(int index, const cv::Mat& /*image*/) override {
    const testing::SimulatedSequence& seq = Sequence();
    DisparityPair p{seq.disparity_left[index] * scale, seq.disparity_right[index] * scale};
    if (damage) Damage(&p.left), Damage(&p.right);
    if (zero) p.left.setTo(0.0f), p.right.setTo(0.0f);
    ++calls;
    return p;
  }
  static void Damage(cv::Mat* m) {
    // Left third NaN, a middle band negative: no point may come from there.
    (*m)(cv::Rect(0, 0, m->cols / 3, m->rows)).setTo(std::numeric_limits<float>::quiet_NaN());
    (*m)(cv::Rect(m->cols / 3, 0, 20, m->rows)).setTo(-5.0f);
  }
  double scale = 1.0;
  bool damage = false;
  bool zero = false;
  std::atomic<int> calls{0};  // a worker thread may call Predict
};

class PointCollector : public OdometryObserver {
 public:
  void OnWindowOptimized(const WindowEvent& e) override {
    if (first.empty()) first = e.points;
  }
  std::vector<PointInfo> first;  // the points of the first window
};

struct DvsoRun {
  Trajectory estimate;
  int lost = 0;
  int keyframes = 0;
  std::vector<PointInfo> first_points;
};

DvsoRun RunDvso(DisparitySource* source, OdometryOptions options, int frames = kFrames) {
  const testing::SimulatedSequence& seq = Sequence();
  options.dvso.virtual_baseline = seq.camera.baseline;
  System system(options, seq.camera, OdometryMode::kDvso, source);
  TrajectoryRecorder recorder;
  PointCollector points;
  system.AddObserver(&recorder);
  system.AddObserver(&points);
  // A right image handed in is ignored: DVSO is monocular.
  for (int i = 0; i < frames; ++i) system.ProcessFrame(i, 0.1 * i, seq.left[i], seq.right[i]);
  system.Finish();
  DvsoRun r;
  r.estimate = recorder.Resolve();
  r.lost = recorder.CountStatus(FrameStatus::kLost);
  r.first_points = points.first;
  r.keyframes = system.num_keyframes_total();
  return r;
}

double MaxTranslationError(const Trajectory& estimate, const testing::SimulatedSequence& seq) {
  double max_err = 0;
  for (size_t i = 0; i < seq.truth.size(); ++i) {
    max_err = std::max(max_err, (estimate.poses[i].T_world_camera.translation() - seq.truth[i].translation()).norm());
  }
  return max_err;
}

TEST(DvsoMode, CapabilitiesOfEachMode) {
  const ModeCapabilities mono = CapabilitiesOf(OdometryMode::kMono);
  EXPECT_FALSE(mono.has_right_image);
  EXPECT_FALSE(mono.has_predictions);
  EXPECT_TRUE(mono.needs_mono_initializer);
  const ModeCapabilities stereo = CapabilitiesOf(OdometryMode::kStereo);
  EXPECT_TRUE(stereo.has_right_image);
  EXPECT_FALSE(stereo.has_predictions);
  EXPECT_FALSE(stereo.needs_mono_initializer);
  const ModeCapabilities dvso = CapabilitiesOf(OdometryMode::kDvso);
  EXPECT_FALSE(dvso.has_right_image);
  EXPECT_TRUE(dvso.has_predictions);
  EXPECT_FALSE(dvso.needs_mono_initializer);
  EXPECT_TRUE(dvso.StartsMetric());
  EXPECT_EQ(ParseOdometryMode("dvso"), OdometryMode::kDvso);
  EXPECT_EQ(ToString(OdometryMode::kDvso), "dvso");
}

TEST(DvsoMode, NeedsASourceAndAVirtualBaseline) {
  const testing::SimulatedSequence& seq = Sequence();
  OracleSource source;
  OdometryOptions options;
  EXPECT_THROW({ System s(options, seq.camera, OdometryMode::kDvso, nullptr); }, Error);
  EXPECT_THROW({ System s(options, seq.camera, OdometryMode::kDvso, &source); }, Error);  // b_v unresolved (0)
  options.dvso.virtual_baseline = 0.5;
  EXPECT_NO_THROW({ System s(options, seq.camera, OdometryMode::kDvso, &source); });
}

TEST(DvsoMode, PredictedIntervalIsCentredOnThePrediction) {
  ImmaturePoint p;
  p.SetPredictedInterval(0.1f, 0.25f, /*converged=*/false);
  EXPECT_FLOAT_EQ(p.idepth_min, 0.075f);
  EXPECT_FLOAT_EQ(p.idepth_max, 0.125f);
  EXPECT_FLOAT_EQ(p.IdepthEstimate(), 0.1f);
  EXPECT_FALSE(p.ReadyForActivation(ImmaturePointOptions{}));  // must be traced first
  p.SetPredictedInterval(0.1f, 0.25f, /*converged=*/true);
  EXPECT_TRUE(p.ReadyForActivation(ImmaturePointOptions{}));   // first keyframe of a map
}

TEST(DvsoMode, FirstKeyframeDepthsComeFromTheLeftPrediction) {
  const testing::SimulatedSequence& seq = Sequence();
  OracleSource source;
  OdometryOptions options;
  options.bundle_adjustment = false;  // depths exactly as initialised
  const DvsoRun r = RunDvso(&source, options, 1);
  ASSERT_GT(r.first_points.size(), 100u);
  const cv::Mat& d_left = seq.disparity_left[0];
  for (const PointInfo& p : r.first_points) {
    const double expected = InverseDepthFromDisparity(d_left.at<float>(static_cast<int>(p.v), static_cast<int>(p.u)),
                                                      seq.camera.left.fx, seq.camera.baseline);
    ASSERT_NEAR(p.idepth, expected, 1e-5 * expected) << p.u << "," << p.v;
  }
}

TEST(DvsoMode, LeftRightCheckRemovesInconsistentPixels) {
  // D^R of frame 0 is shifted by +3 px in the right half of its columns. A pixel
  // whose exact maps agree (e_lr <= 1 px) and whose match p - D^L(p) lies in that
  // half then has e_lr >= 3 - 1 = 2 px (both bilinear taps moved by 3): the check
  // must remove every such pixel, and without it they are selected. Pixels that
  // disagree already in the exact maps (occlusion edges, where the bilinear D^R
  // mixes two surfaces) are not this test's subject: the shift can bring some of
  // them within 1 px.
  class InconsistentSource : public OracleSource {
   public:
    DisparityPair Predict(int index, const cv::Mat& image) override {
      DisparityPair p = OracleSource::Predict(index, image);
      p.right(cv::Rect(p.right.cols / 2, 0, p.right.cols / 2, p.right.rows)) += 3.0f;
      return p;
    }
  };
  const testing::SimulatedSequence& seq = Sequence();
  auto count_inconsistent = [&](bool check) {
    InconsistentSource source;
    OdometryOptions options;
    options.bundle_adjustment = false;
    options.dvso.left_right_check = check;
    int n = 0;
    for (const PointInfo& p : RunDvso(&source, options, 1).first_points) {
      const int u = static_cast<int>(p.u), v = static_cast<int>(p.v);
      const float d = seq.disparity_left[0].at<float>(v, u);
      const bool consistent = LeftRightDisparityError(seq.disparity_left[0], seq.disparity_right[0], u, v) <= 1.0f;
      if (consistent && u - d >= seq.camera.left.width / 2) ++n;  // its match lies in the shifted half
    }
    return n;
  };
  EXPECT_EQ(count_inconsistent(true), 0);
  EXPECT_GT(count_inconsistent(false), 20);
}


TEST(DvsoMode, ExactPredictionsGiveAMetricTrajectoryWithoutAlignment) {
  const testing::SimulatedSequence& seq = Sequence();
  OracleSource source;
  const DvsoRun r = RunDvso(&source, OdometryOptions{});
  ASSERT_EQ(r.estimate.size(), seq.truth.size());
  EXPECT_EQ(r.lost, 0);
  const double ratio = r.estimate.PathLength() / seq.path_length;
  const double max_err = MaxTranslationError(r.estimate, seq);
  std::cout << "dvso oracle: length ratio " << ratio << ", max error " << max_err << " m over " << seq.path_length
            << " m, " << source.calls << " predictions\n";
  EXPECT_NEAR(ratio, 1.0, 0.01);
  EXPECT_LT(max_err, 0.01 * seq.path_length);
  EXPECT_LT(source.calls, kFrames);  // only keyframes ask for predictions
}

TEST(DvsoMode, DepthInitialisationAloneTracksEveryFrame) {
  // Ablation row "in": no virtual stereo term. The first keyframe's points
  // then have no residual until the second keyframe and must survive.
  const testing::SimulatedSequence& seq = Sequence();
  OracleSource source;
  OdometryOptions options;
  options.window.use_virtual_stereo = false;
  options.dvso.left_right_check = false;
  const DvsoRun r = RunDvso(&source, options);
  EXPECT_EQ(r.lost, 0);
  EXPECT_NEAR(r.estimate.PathLength() / seq.path_length, 1.0, 0.05);
}


// The oracle behind a worker, taking as long as a small network.
class SlowOracle : public OracleSource {
 public:
  DisparityPair Predict(int index, const cv::Mat& image) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(40));
    return OracleSource::Predict(index, image);
  }
};

TEST(DvsoMode, EveryPredictionTimingOnAWorkerStaysMetric) {
  const testing::SimulatedSequence& seq = Sequence();
  for (const std::string timing : {"keyframe-async", "keyframe-blocking", "speculative"}) {
    auto slow = std::make_unique<SlowOracle>();
    const SlowOracle* oracle = slow.get();
    AsyncDisparitySource worker(std::move(slow));
    OdometryOptions options;
    options.dvso.prediction_timing = timing;
    const DvsoRun r = RunDvso(&worker, options);
    EXPECT_EQ(r.lost, 0) << timing;
    const double ratio = r.estimate.PathLength() / seq.path_length;
    std::cout << timing << ": length ratio " << ratio << ", max error " << MaxTranslationError(r.estimate, seq)
              << " m, " << oracle->calls << " predictions, " << worker.prefetched_used() << " requested ahead\n";
    EXPECT_NEAR(ratio, 1.0, 0.01) << timing;
    EXPECT_LT(MaxTranslationError(r.estimate, seq), 0.01 * seq.path_length) << timing;
    if (timing == "speculative") {
      EXPECT_GT(oracle->calls, worker.prefetched_used());  // predicted frames that did not become keyframes
    } else {
      EXPECT_LT(oracle->calls, kFrames);  // only keyframes
    }
    if (timing == "keyframe-async") {
      EXPECT_GT(worker.prefetched_used(), 5);  // attached after the keyframe was made
      // Every keyframe's prediction is collected, the last one's too (at Finish: a model error there
      // must fail the run, not vanish with the worker's result).
      EXPECT_EQ(worker.prefetched_used() + worker.computed_on_demand(), r.keyframes);
    }
  }
}

// The oracle as a worker whose result is never there before the odometry
// waits for it: every keyframe-async prediction lands at the next keyframe,
// as on fast real driving where nearly every frame becomes a keyframe.
class NeverReadyOracle : public OracleSource {
 public:
  bool IsReady(int /*index*/) override { return false; }
};

class ActivePointCounter : public OdometryObserver {
 public:
  void OnFrameTracked(const FrameEvent& e) override {
    if (e.status == FrameStatus::kLost) return;
    sum += e.active_points;
    ++frames;
  }
  double Mean() const { return frames > 0 ? sum / frames : 0.0; }
  double sum = 0;
  int frames = 0;
};

TEST(DvsoMode, LatePredictionsStillGiveTheWindowItsPoints) {
  // A keyframe whose prediction arrives with the next keyframe gets its
  // candidates then; they are traced against that (already tracked) frame at
  // once, so they can be activated in the same step as with the blocking
  // schedule instead of a keyframe later (which emptied the window on real
  // KITTI: 2-3x fewer points).
  const testing::SimulatedSequence& seq = Sequence();
  double mean_points[2] = {0, 0};
  for (int late = 0; late < 2; ++late) {
    NeverReadyOracle never_ready;
    OracleSource immediate;
    OdometryOptions options;
    options.dvso.prediction_timing = late ? "keyframe-async" : "keyframe-blocking";
    options.dvso.virtual_baseline = seq.camera.baseline;
    System system(options, seq.camera, OdometryMode::kDvso, late ? &never_ready : &immediate);
    ActivePointCounter counter;
    TrajectoryRecorder recorder;
    system.AddObserver(&counter);
    system.AddObserver(&recorder);
    for (int i = 0; i < kFrames; ++i) system.ProcessFrame(i, 0.1 * i, seq.left[i]);
    system.Finish();
    EXPECT_EQ(recorder.CountStatus(FrameStatus::kLost), 0);
    const Trajectory estimate = recorder.Resolve();
    EXPECT_NEAR(estimate.PathLength() / seq.path_length, 1.0, 0.01) << (late ? "late" : "blocking");
    mean_points[late] = counter.Mean();
  }
  std::cout << "mean active points: blocking " << mean_points[0] << ", predictions one keyframe late "
            << mean_points[1] << "\n";
  EXPECT_GT(mean_points[1], 0.85 * mean_points[0]);
}

TEST(DvsoMode, APendingPredictionIsCollectedWhenTrackingIsLost) {
  // A corrupt frame loses tracking while the last keyframe's prediction is still pending (this source
  // is never ready before it is waited for). The request is still collected, so a model error in it
  // fails the run as anywhere else: every keyframe's prediction is fetched exactly once.
  const testing::SimulatedSequence& seq = Sequence();
  NeverReadyOracle source;
  OdometryOptions options;
  options.dvso.virtual_baseline = seq.camera.baseline;
  System system(options, seq.camera, OdometryMode::kDvso, &source);
  TrajectoryRecorder recorder;
  system.AddObserver(&recorder);
  for (int i = 0; i < kFrames; ++i) {
    cv::Mat image = seq.left[i].clone();
    if (i == kFrames / 2) cv::randu(image, 0, 255);
    system.ProcessFrame(i, 0.1 * i, image);
  }
  system.Finish();
  ASSERT_GE(system.num_resets(), 1);
  EXPECT_EQ(source.calls, system.num_keyframes_total());
}

TEST(DvsoMode, TrajectoryScaleFollowsThePredictionScale) {
  const testing::SimulatedSequence& seq = Sequence();
  OracleSource source;
  source.scale = 1.1;  // disparities 10 % too large: everything 10 % closer
  const DvsoRun r = RunDvso(&source, OdometryOptions{});
  EXPECT_EQ(r.lost, 0);
  const double ratio = r.estimate.PathLength() / seq.path_length;
  std::cout << "dvso, disparities x1.1: length ratio " << ratio << "\n";
  EXPECT_NEAR(ratio, 1.0 / 1.1, 0.015);
}

TEST(DvsoMode, NaNZeroAndNegativePredictionsAreSkippedNotFatal) {
  const testing::SimulatedSequence& seq = Sequence();
  OracleSource damaged;
  damaged.damage = true;
  OdometryOptions options;
  options.bundle_adjustment = false;
  const DvsoRun first = RunDvso(&damaged, options, 1);
  ASSERT_GT(first.first_points.size(), 50u);
  for (const PointInfo& p : first.first_points) {
    EXPECT_GE(p.u, seq.camera.left.width / 3 + 20) << "point from a NaN / negative prediction";
    EXPECT_TRUE(std::isfinite(p.idepth) && p.idepth > 0);
  }
  OracleSource damaged_full;
  damaged_full.damage = true;
  const DvsoRun r = RunDvso(&damaged_full, OdometryOptions{});
  ASSERT_EQ(r.estimate.size(), seq.truth.size());
  for (const StampedPose& pose : r.estimate.poses) EXPECT_TRUE(pose.T_world_camera.matrix().allFinite());
  // No prediction at all: no points, every frame lost, but no crash and no NaN pose.
  OracleSource empty;
  empty.zero = true;
  const DvsoRun none = RunDvso(&empty, OdometryOptions{}, 10);
  ASSERT_EQ(none.estimate.size(), 10u);
  for (const StampedPose& pose : none.estimate.poses) EXPECT_TRUE(pose.T_world_camera.matrix().allFinite());
}

}  // namespace
}  // namespace dvso::vo

namespace dvso::vo {
namespace {

TEST(DvsoCli, RunsOnDisparityFilesAndRejectsBadInputWithOneLineNothingWritten) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_mode_cli", 12);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const std::string files = " --disparity-left " + seq + "/disp_0 --disparity-right " + seq + "/disp_1";
  const auto good = dvso::testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " + dir +
                                           "/good" + files);
  ASSERT_EQ(good.exit_code, 0) << good.out;
  EXPECT_NE(good.out.find("virtual baseline"), std::string::npos);
  EXPECT_EQ(ReadTrajectory(dir + "/good/trajectory.txt", TrajectoryFormat::kKitti).size(), 12u);
  const std::string log = dvso::testing::ReadText(dir + "/good/run_log.csv");
  EXPECT_NE(log.find("virtual_stereo_residuals,virtual_stereo_energy"), std::string::npos);

  // A missing map: one line naming the file, exit 1, no output files.
  std::filesystem::remove(seq + "/disp_1/000007.png");
  const auto missing = dvso::testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " +
                                              dir + "/missing" + files);
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.out.find("disp_1/000007.png"), std::string::npos) << missing.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/missing/trajectory.txt"));
  EXPECT_FALSE(std::filesystem::exists(dir + "/missing/run_log.csv"));

  // A model file that is not TorchScript (or a build without LibTorch): one clear line.
  std::ofstream(dir + "/fake.pt") << "not a model";
  const auto fake = dvso::testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " + dir +
                                           "/fake --model " + dir + "/fake.pt");
  EXPECT_EQ(fake.exit_code, 1);
  EXPECT_NE(fake.out.find(dir + "/fake.pt"), std::string::npos) << fake.out;
  EXPECT_FALSE(std::filesystem::exists(dir + "/fake/trajectory.txt"));

  // A .npy stack of the wrong dtype.
  std::ofstream(dir + "/bad.npy", std::ios::binary)
      << std::string("\x93NUMPY\x01\x00", 8) << std::string("\x53\x00", 2)
      << "{'descr': '<f8', 'fortran_order': False, 'shape': (12, 96, 320), }                \n";
  const auto dtype = dvso::testing::RunDvso("odometry --mode dvso --no-progress --sequence " + seq + " --out " + dir +
                                            "/dtype --disparity-left " + dir + "/bad.npy --disparity-right " + dir +
                                            "/bad.npy");
  EXPECT_EQ(dtype.exit_code, 1);
  EXPECT_NE(dtype.out.find("bad.npy"), std::string::npos) << dtype.out;
  // Prediction options outside dvso mode are a usage error.
  EXPECT_NE(dvso::testing::RunDvso("odometry --mode mono --sequence " + seq + " --out " + dir + "/m" + files).exit_code,
            0);
}


TEST(DvsoCli, AblationAndTuneBaselinePrintEveryRow) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_ablation_cli", 15);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const std::string common = " --sequence " + seq + " --gt " + seq + "/poses.txt --disparity-left " + seq +
                             "/disp_0 --disparity-right " + seq + "/disp_1 --preset fast";
  const auto ablation = dvso::testing::RunDvso("ablation --json --tuned-baseline 0.55 --out " + dir + "/abl" + common,
                                               /*merge_stderr=*/false);
  ASSERT_EQ(ablation.exit_code, 0) << ablation.out;
  const nlohmann::json j = nlohmann::json::parse(ablation.out);
  ASSERT_EQ(j["variants"].size(), 6u);
  const char* names[] = {"mono", "in", "in+vs", "in+vs+lr", "in+vs+tb", "full"};
  for (int i = 0; i < 6; ++i) EXPECT_EQ(j["variants"][i]["name"], names[i]);
  EXPECT_TRUE(j["variants"][0]["aligned"].get<bool>());   // mono is the Sim(3)-aligned reference
  EXPECT_FALSE(j["variants"][5]["aligned"].get<bool>());
  // Exact disparities: the metric rows need no scale correction; the tb rows use b_v = 0.55 instead of 0.537.
  EXPECT_NEAR(j["variants"][2]["sim3_scale"].get<double>(), 1.0, 0.03);
  EXPECT_NEAR(j["variants"][5]["sim3_scale"].get<double>(), 0.537 / 0.55, 0.03);
  const auto tune = dvso::testing::RunDvso("tune-baseline --json --values 0.45:0.09:0.63 --out " + dir + "/tune" +
                                           common, /*merge_stderr=*/false);
  ASSERT_EQ(tune.exit_code, 0) << tune.out;
  const nlohmann::json t = nlohmann::json::parse(tune.out);
  ASSERT_EQ(t["runs"].size(), 3u);
  EXPECT_NEAR(t["best_virtual_baseline"].get<double>(), 0.54, 1e-9);  // the true baseline is 0.537
  EXPECT_NE(dvso::testing::RunDvso("tune-baseline --values 0.6:0.1:0.3 --out " + dir + "/bad" + common).exit_code, 0);
  // Experiments default to the deterministic schedule, written into every run's config.yaml; a config file's
  // dvso.prediction_timing and then the flag still decide.
  EXPECT_EQ(j["prediction_timing"], "keyframe-blocking");
  EXPECT_EQ(t["prediction_timing"], "keyframe-blocking");
  const std::string saved = dvso::testing::ReadText(dir + "/abl/full/config.yaml");
  EXPECT_NE(saved.find("prediction_timing: keyframe-blocking"), std::string::npos) << saved;
  std::ofstream(dir + "/async.yaml") << "dvso:\n  prediction_timing: keyframe-async\n";
  const std::string one_run = " --json --values 0.54:0.1:0.54 --count 8";
  const auto from_config = dvso::testing::RunDvso("tune-baseline --out " + dir + "/t_config --config " + dir +
                                                  "/async.yaml" + one_run + common, /*merge_stderr=*/false);
  ASSERT_EQ(from_config.exit_code, 0) << from_config.out;
  EXPECT_EQ(nlohmann::json::parse(from_config.out)["prediction_timing"], "keyframe-async");
  const auto from_flag = dvso::testing::RunDvso("tune-baseline --out " + dir + "/t_flag --config " + dir +
                                                "/async.yaml --prediction-schedule speculative" + one_run + common,
                                                /*merge_stderr=*/false);
  ASSERT_EQ(from_flag.exit_code, 0) << from_flag.out;
  EXPECT_EQ(nlohmann::json::parse(from_flag.out)["prediction_timing"], "speculative");
  // A config file's b_v is the rows' default as in `dvso odometry`; --virtual-baseline still wins over it.
  std::ofstream(dir + "/bv.yaml") << "dvso:\n  virtual_baseline: 0.5\n";
  const std::string short_ablation = "ablation --json --tuned-baseline 0.55 --count 8 --config " + dir + "/bv.yaml";
  const auto bv_config = dvso::testing::RunDvso(short_ablation + " --out " + dir + "/abl_bv" + common,
                                                /*merge_stderr=*/false);
  ASSERT_EQ(bv_config.exit_code, 0) << bv_config.out;
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(bv_config.out)["virtual_baseline_default"].get<double>(), 0.5);
  // The printed prediction line names the b_v the rows use, not the files' own 0.537 m alone.
  const std::string described = nlohmann::json::parse(bv_config.out)["predictions"].get<std::string>();
  EXPECT_NE(described.find("dvso.virtual_baseline 0.5 m is used instead"), std::string::npos) << described;
  const auto bv_flag = dvso::testing::RunDvso(short_ablation + " --virtual-baseline 0.45 --out " + dir + "/abl_bvf" +
                                              common, /*merge_stderr=*/false);
  ASSERT_EQ(bv_flag.exit_code, 0) << bv_flag.out;
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(bv_flag.out)["virtual_baseline_default"].get<double>(), 0.45);

  // Several sequences (the paper tunes b_v on its training set): every value runs on each, the lowest mean
  // error wins. The same sequence twice, the second cut shorter, so the two runs differ.
  const std::string two = " --json --values 0.45:0.09:0.63 --preset fast --disparity-left " + seq +
                          "/disp_0 --disparity-right " + seq + "/disp_1 --sequence " + seq + " --gt " + seq +
                          "/poses.txt --sequence " + seq + " --gt " + seq + "/poses.txt";
  const auto files_two = dvso::testing::RunDvso("tune-baseline --out " + dir + "/two" + two);
  EXPECT_NE(files_two.exit_code, 0);  // disparity files belong to one sequence
  EXPECT_NE(files_two.out.find("several --sequence"), std::string::npos) << files_two.out;
  const auto unpaired = dvso::testing::RunDvso("tune-baseline --out " + dir + "/unpaired" + common + " --sequence " + seq);
  EXPECT_NE(unpaired.exit_code, 0);
  EXPECT_NE(unpaired.out.find("one --gt per --sequence"), std::string::npos) << unpaired.out;
  EXPECT_NE(dvso::testing::RunDvso("ablation --out " + dir + "/abl2" + common + " --sequence " + seq + " --gt " + seq +
                                   "/poses.txt").exit_code, 0);  // the ablation table is per sequence
}

// Frames of the sequences the tests below simulate: a few, enough for the odometry to start.
constexpr int kShortCliFrames = 8;

// --sequence / --gt / disparity files of a simulated sequence, fast preset.
std::string FilesExperimentArgs(const std::string& seq, const std::string& gt) {
  return " --sequence " + seq + " --gt " + gt + " --disparity-left " + seq + "/disp_0 --disparity-right " + seq +
         "/disp_1 --preset fast";
}

// The sequence's GT with every position scaled about the origin, written to `path`: the same images, but a
// GT path long enough for a KITTI segment (only the evaluation reads the GT, never the odometry).
void WriteStretchedGt(const std::string& seq, const std::string& path) {
  constexpr double kStretch = 20;  // kShortCliFrames frames of ~1 m -> ~140 m, over the shortest segment (100 m)
  Trajectory gt = ReadTrajectory(seq + "/poses.txt", TrajectoryFormat::kKitti);
  for (StampedPose& pose : gt.poses) pose.T_world_camera.translation() *= kStretch;
  WriteKittiTrajectory(path, gt);
}

// Whether `out_dir` holds a run folder of tune-baseline (bv_*).
bool HasBaselineRunFolder(const std::string& out_dir) {
  if (!std::filesystem::is_directory(out_dir)) return false;
  for (const auto& entry : std::filesystem::directory_iterator(out_dir)) {
    if (entry.path().filename().string().rfind("bv_", 0) == 0) return true;
  }
  return false;
}

TEST(DvsoCli, TuneBaselineNamesItsMetricAndScoresByTRelOnlyWithSegments) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_tune_metric", kShortCliFrames);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const std::string one_value = "tune-baseline --json --values 0.54:0.1:0.54";
  // A path of ~7 m has no KITTI segment: the ATE is the error, t_rel / r_rel are null, not 0.
  const auto short_run = dvso::testing::RunDvso(one_value + " --out " + dir + "/short" +
                                                FilesExperimentArgs(seq, seq + "/poses.txt"), /*merge_stderr=*/false);
  ASSERT_EQ(short_run.exit_code, 0) << short_run.out;
  const nlohmann::json s = nlohmann::json::parse(short_run.out);
  EXPECT_EQ(s.value("error_metric", std::string()), "ate_m");
  EXPECT_EQ(s["runs"][0]["segments"].get<int>(), 0);
  EXPECT_TRUE(s["runs"][0]["t_rel"].is_null());
  EXPECT_TRUE(s["runs"][0]["r_rel"].is_null());
  EXPECT_DOUBLE_EQ(s["mean_error"][0]["mean_error"].get<double>(), s["runs"][0]["ate_rmse"].get<double>());
  // The same images against a GT path over 100 m: t_rel.
  WriteStretchedGt(seq, dir + "/long_gt.txt");
  const auto long_run = dvso::testing::RunDvso(one_value + " --out " + dir + "/long" +
                                               FilesExperimentArgs(seq, dir + "/long_gt.txt"), /*merge_stderr=*/false);
  ASSERT_EQ(long_run.exit_code, 0) << long_run.out;
  const nlohmann::json l = nlohmann::json::parse(long_run.out);
  EXPECT_EQ(l.value("error_metric", std::string()), "t_rel_percent");
  EXPECT_GT(l["runs"][0]["segments"].get<int>(), 0);
  EXPECT_DOUBLE_EQ(l["mean_error"][0]["mean_error"].get<double>(), l["runs"][0]["t_rel"].get<double>());
}

// Several sequences need a model (disparity files belong to one sequence), so only builds with LibTorch
// have this test (tests/CMakeLists.txt defines DVSO_WITH_TORCH for them).
#ifdef DVSO_WITH_TORCH
TEST(DvsoCli, TuneBaselineScoresEverySequenceByAteWhenOneIsTooShortForSegments) {
  const std::string model = std::string(DVSO_TEST_DATA_DIR) + "/../models/stacknet_cpu_main.pt";
  ASSERT_TRUE(std::filesystem::exists(model));
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_tune_mixed", kShortCliFrames);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  WriteStretchedGt(seq, dir + "/long_gt.txt");
  const auto run = dvso::testing::RunDvso("tune-baseline --json --values 0.54:0.1:0.54 --preset fast --model " +
                                              model + " --sequence " + seq + " --gt " + dir + "/long_gt.txt" +
                                              " --sequence " + seq + " --gt " + seq + "/poses.txt --out " + dir +
                                              "/mixed",
                                          /*merge_stderr=*/false);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  EXPECT_EQ(j.value("error_metric", std::string()), "ate_m");
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_GT(j["runs"][0]["segments"].get<int>(), 0);  // t_rel exists there, yet the search does not mix units
  EXPECT_EQ(j["runs"][1]["segments"].get<int>(), 0);
  const double mean_ate = 0.5 * (j["runs"][0]["ate_rmse"].get<double>() + j["runs"][1]["ate_rmse"].get<double>());
  EXPECT_NEAR(j["mean_error"][0]["mean_error"].get<double>(), mean_ate, 1e-12);
}
#endif  // DVSO_WITH_TORCH

TEST(DvsoCli, TuneBaselineChecksWriteModelBeforeAnyRun) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_tune_write_model", kShortCliFrames);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const auto files = dvso::testing::RunDvso("tune-baseline --values 0.5:0.04:0.58 --write-model " + dir +
                                            "/tuned.pt --out " + dir + "/files" +
                                            FilesExperimentArgs(seq, seq + "/poses.txt"));
  EXPECT_NE(files.exit_code, 0);
  EXPECT_NE(files.out.find("--write-model"), std::string::npos) << files.out;
  EXPECT_FALSE(HasBaselineRunFolder(dir + "/files"));
  // A missing output folder is refused before the model is even opened (so in builds without LibTorch too).
  const std::string model = std::string(DVSO_TEST_DATA_DIR) + "/../models/stacknet_cpu_main.pt";
  const auto no_folder = dvso::testing::RunDvso("tune-baseline --values 0.5:0.04:0.58 --preset fast --model " + model +
                                                " --write-model " + dir + "/absent/tuned.pt --sequence " + seq +
                                                " --gt " + seq + "/poses.txt --out " + dir + "/no_folder");
  EXPECT_NE(no_folder.exit_code, 0);
  EXPECT_NE(no_folder.out.find(dir + "/absent"), std::string::npos) << no_folder.out;
  EXPECT_FALSE(HasBaselineRunFolder(dir + "/no_folder"));
}

TEST(DvsoCli, TablesPrintADashForTRelWithoutSegments) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_table_dash", kShortCliFrames);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const auto run = dvso::testing::RunDvso("tune-baseline --values 0.54:0.1:0.54 --out " + dir + "/table" +
                                              FilesExperimentArgs(seq, seq + "/poses.txt"),
                                          /*merge_stderr=*/false);  // the progress bar stays out of the table
  ASSERT_EQ(run.exit_code, 0) << run.out;
  EXPECT_NE(run.out.find("error minimised: ATE m"), std::string::npos) << run.out;
  const size_t row = run.out.find("\nb_v=");  // the one run's row
  ASSERT_NE(row, std::string::npos) << run.out;
  std::istringstream cells(run.out.substr(row + 1, run.out.find('\n', row + 1) - row - 1));
  std::string name, t_rel, r_rel;
  cells >> name >> t_rel >> r_rel;
  EXPECT_EQ(t_rel, "-") << run.out;
  EXPECT_EQ(r_rel, "-") << run.out;
}

TEST(DvsoCli, TuneBaselineRunNamesKeepCloseValuesApart) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_tune_names", kShortCliFrames);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const std::string files = FilesExperimentArgs(seq, seq + "/poses.txt");
  const auto run = dvso::testing::RunDvso("tune-baseline --json --values 0.5:0.0004:0.5008 --out " + dir + "/close" +
                                              files, /*merge_stderr=*/false);
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const nlohmann::json j = nlohmann::json::parse(run.out);
  ASSERT_EQ(j["runs"].size(), 3u);
  const char* names[] = {"0.5", "0.5004", "0.5008"};
  for (int v = 0; v < 3; ++v) {
    EXPECT_EQ(j["runs"][v]["name"], std::string("b_v=") + names[v]);
    EXPECT_TRUE(std::filesystem::exists(dir + "/close/bv_" + names[v] + "/trajectory.txt")) << names[v];
  }
  // Grid values are the decimals the user meant: 0.4 + 0.02 is 0.42000000000000004 in binary, which the JSON
  // (and a tuned model's metadata) would print in full.
  const auto binary = dvso::testing::RunDvso("tune-baseline --json --values 0.4:0.02:0.42 --out " + dir + "/binary" +
                                                 files, /*merge_stderr=*/false);
  ASSERT_EQ(binary.exit_code, 0) << binary.out;
  const nlohmann::json jb = nlohmann::json::parse(binary.out);
  ASSERT_EQ(jb["mean_error"].size(), 2u);
  EXPECT_EQ(jb["mean_error"][1]["virtual_baseline"].dump(), "0.42");
  // Values no run name tells apart are refused before any run.
  const auto colliding = dvso::testing::RunDvso("tune-baseline --values 0.5:0.0000001:0.5000002 --out " + dir +
                                                "/colliding" + files);
  EXPECT_NE(colliding.exit_code, 0);
  EXPECT_NE(colliding.out.find("share the run name"), std::string::npos) << colliding.out;
  EXPECT_FALSE(HasBaselineRunFolder(dir + "/colliding"));
}

TEST(DvsoCli, AblationRejectsMalformedTuneValuesEvenWithATunedBaseline) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("dvso_ablation_tune_values", kShortCliFrames);
  ASSERT_FALSE(dir.empty());
  const std::string seq = dir + "/seq";
  const std::string files = FilesExperimentArgs(seq, seq + "/poses.txt");
  for (const std::string values : {"0.6:0.1:0.3", "abc"}) {
    const auto run = dvso::testing::RunDvso("ablation --tuned-baseline 0.55 --tune-values " + values + " --out " +
                                            dir + "/abl" + files);
    EXPECT_NE(run.exit_code, 0) << values;
    // The option the user typed, not tune-baseline's --values.
    EXPECT_NE(run.out.find("--tune-values '" + values + "'"), std::string::npos) << run.out;
    EXPECT_FALSE(std::filesystem::exists(dir + "/abl/mono")) << values;
  }
}

}  // namespace
}  // namespace dvso::vo
