// `dvso labels` end to end on a short simulated stereo sequence (small image
// so CI stays short): every frame gets a label file, labels agree with the
// exact GT disparity, and a second run resumes without recomputing.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "core/disparity_io.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "core/simulator.h"
#include "core/sequence.h"
#include "sdso_labels/label_runner.h"
#include "sdso_labels/pair_cache.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;
using namespace dvso;

namespace {

constexpr int kFrames = 40;

const std::string& SimulatedSequenceDir() {
  static const std::string dir = [] {
    const std::string out = dvso::testing::ScratchPath("labels_e2e");
    SimulatorOptions o;
    o.trajectory_path = std::string(DVSO_TEST_DATA_DIR) + "/kitti_poses/00.txt";
    o.num_frames = kFrames;
    o.camera = StereoCamera{}.Resized(416, 128);
    o.texture_size = 256;
    WriteSimulatedSequence(o, out, false);
    return out;
  }();
  return dir;
}

}  // namespace

TEST(LabelsEndToEnd, EveryFrameLabelledAndAccurateThenResumes) {
  const std::string seq = SimulatedSequenceDir();
  const std::string out = seq + "_labels";
  labels::LabelRunOptions options;
  options.progress = false;
  options.gt_disparity_dir = seq + "/disp_0";
  options.gt_disparity_right_dir = seq + "/disp_1";
  options.labels.right_labels = true;
  const labels::LabelRunSummary first = labels::RunLabelExtraction(seq, out, options);
  EXPECT_FALSE(first.skipped_complete);
  EXPECT_EQ(first.statistics.frames(), kFrames);
  for (int i = 0; i < kFrames; ++i) {
    const cv::Mat labels = ReadKittiMapPng(JoinPath(out, FrameFileName(i, ".png")));
    EXPECT_EQ(labels.cols, 416);
    EXPECT_EQ(labels.rows, 128);
  }
  // Measured: ~1170 labels/frame, 99.4 % within 1 px, MAE 0.12 px (416x128, 40 frames).
  EXPECT_GT(first.statistics.mean_labels_per_frame(), 500.0);
  ASSERT_GT(first.statistics.min_labels_per_frame(), 0);  // so a 0 below can only come from the emptied file
  EXPECT_GT(first.statistics.compared(), 20000);
  EXPECT_GT(first.statistics.share_within_1px(), 0.95);
  EXPECT_LT(first.statistics.mean_absolute_error(), 0.5);
  EXPECT_NEAR(first.verified_labels, first.statistics.mean_labels_per_frame() * kFrames, 0.5);
  EXPECT_GT(first.projected_labels, first.verified_labels);  // the stereo check removed some
  // Right-image labels: as many and as accurate (the simulator's disp_1 is the right GT).
  EXPECT_GT(first.right_statistics.mean_labels_per_frame(), 500.0);
  EXPECT_GT(first.right_statistics.share_within_1px(), 0.95);
  EXPECT_TRUE(fs::exists(JoinPath(out, "right/000039.png")));
  EXPECT_TRUE(fs::exists(out + "/labels_summary.json"));
  {
    // The pair the labels were made on, which training checks against the pair it reads.
    std::ifstream summary(out + "/labels_summary.json");
    const std::string text((std::istreambuf_iterator<char>(summary)), std::istreambuf_iterator<char>());
    EXPECT_NE(text.find("\"cameras\": \"grey\""), std::string::npos) << text;
  }
  EXPECT_TRUE(fs::exists(out + "/odometry/trajectory.txt"));

  // Resume: all files exist, nothing is recomputed, the summary is the same; the temporary files a
  // killed run leaves (WriteAtomically) are removed.
  std::ofstream(JoinPath(out, "000004.tmp-writing.png")) << "half a PNG";
  std::ofstream(JoinPath(out, "right/000004.tmp-writing.png")) << "half a PNG";
  const labels::LabelRunSummary second = labels::RunLabelExtraction(seq, out, options);
  EXPECT_FALSE(fs::exists(JoinPath(out, "000004.tmp-writing.png")));
  EXPECT_FALSE(fs::exists(JoinPath(out, "right/000004.tmp-writing.png")));
  EXPECT_TRUE(second.skipped_complete);
  EXPECT_EQ(second.statistics.compared(), first.statistics.compared());
  EXPECT_NEAR(second.statistics.share_within_1px(), first.statistics.share_within_1px(), 0.01);

  // A missing right-image file makes the run incomplete: it is recomputed.
  fs::remove(JoinPath(out, "right/000007.png"));
  EXPECT_FALSE(labels::RunLabelExtraction(seq, out, options).skipped_complete);
  EXPECT_TRUE(fs::exists(JoinPath(out, "right/000007.png")));
  // A missing file makes the run incomplete again: it is recomputed, the files already there are
  // kept, and the statistics are those of the files on disk (frame 3 emptied by hand: 0 labels).
  fs::remove(JoinPath(out, FrameFileName(5, ".png")));
  const std::string frame3 = JoinPath(out, FrameFileName(3, ".png"));
  WriteKittiMapPng(frame3, cv::Mat::zeros(128, 416, CV_32FC1));
  const labels::LabelRunSummary third = labels::RunLabelExtraction(seq, out, options);
  EXPECT_FALSE(third.skipped_complete);
  EXPECT_TRUE(fs::exists(JoinPath(out, FrameFileName(5, ".png"))));
  EXPECT_EQ(third.kept_existing_frames, kFrames - 1);
  EXPECT_EQ(cv::countNonZero(ReadKittiMapPng(frame3)), 0) << "an existing file was rewritten";
  EXPECT_EQ(third.statistics.min_labels_per_frame(), 0) << "statistics of computed maps, not of the files";
  EXPECT_GT(third.statistics.mean_labels_per_frame(), 500.0);

  // A kept file of another size (a folder left from another sequence) is an error naming it, raised
  // before the odometry runs: the missing frame 9 is not recomputed, the odd file is not replaced.
  fs::remove(JoinPath(out, FrameFileName(9, ".png")));
  const std::string frame20 = JoinPath(out, FrameFileName(20, ".png"));
  WriteKittiMapPng(frame20, cv::Mat::zeros(64, 208, CV_32FC1));
  try {
    labels::RunLabelExtraction(seq, out, options);
    ADD_FAILURE() << "a kept label map of the wrong size was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(frame20), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("208x64"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(JoinPath(out, FrameFileName(9, ".png"))));
  EXPECT_EQ(ReadKittiMapPng(frame20).cols, 208);
}

TEST(LabelsEndToEnd, BatchListAndErrors) {
  const std::string seq = SimulatedSequenceDir();
  const std::string list = seq + "_list.txt";
  std::ofstream(list) << "# sequences\n" << seq << "\n\n";
  const auto sequences = labels::ReadSequenceList(list);
  ASSERT_EQ(sequences.size(), 1u);
  EXPECT_EQ(sequences[0], seq);
  std::ofstream(list) << "# nothing\n";
  EXPECT_THROW(labels::ReadSequenceList(list), Error);
  labels::LabelRunOptions options;
  options.progress = false;
  options.gt_disparity_dir = seq + "/no_such_dir";
  EXPECT_THROW(labels::RunLabelExtraction(seq, seq + "_bad", options), Error);
  // Ground truth of another resolution: an error naming the file, before any odometry (no label written).
  const std::string small_gt = seq + "_small_gt";
  fs::create_directories(small_gt);
  for (int i = 0; i < kFrames; ++i) {
    WriteKittiMapPng(JoinPath(small_gt, FrameFileName(i, ".png")), cv::Mat(64, 208, CV_32FC1, cv::Scalar(10.0f)));
  }
  options.gt_disparity_dir = small_gt;
  try {
    labels::RunLabelExtraction(seq, seq + "_small", options);
    ADD_FAILURE() << "ground truth of another size accepted";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(JoinPath(small_gt, "000000.png")), std::string::npos) << what;
    EXPECT_NE(what.find("208x64"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(seq + "_small/000000.png"));
  // A resume into labels of another camera pair would keep them under this run's pair: refused unless
  // --overwrite rewrites them.
  options.gt_disparity_dir.clear();
  fs::create_directories(seq + "_pair");
  std::ofstream(seq + "_pair/labels_summary.json") << "{\"cameras\": \"colour\"}";
  try {
    labels::RunLabelExtraction(seq, seq + "_pair", options);
    ADD_FAILURE() << "labels of the colour pair resumed on the grey pair";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("--overwrite"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(seq + "_pair/000000.png"));
}

TEST(LabelsEndToEnd, ConfigIsStrict) {
  const std::string dir = SimulatedSequenceDir() + "_cfg";
  fs::create_directories(dir);
  std::ofstream(dir + "/ok.yaml") << "preset: fast\nlabels:\n  min_good_residuals: 3\nodometry:\n  active_points: 500\n";
  const labels::LabelRunOptions ok = labels::LoadLabelRunOptions(dir + "/ok.yaml");
  EXPECT_EQ(ok.labels.min_good_residuals, 3);
  EXPECT_EQ(ok.odometry.active_points, 500);
  std::ofstream(dir + "/typo.yaml") << "labels:\n  min_good_residual: 3\n";
  EXPECT_THROW(labels::LoadLabelRunOptions(dir + "/typo.yaml"), Error);
  std::ofstream(dir + "/typo2.yaml") << "odometry:\n  active_pints: 3\n";
  EXPECT_THROW(labels::LoadLabelRunOptions(dir + "/typo2.yaml"), Error);
}

TEST(LabelsEndToEnd, ShippedDefaultConfigEqualsBuiltInDefaults) {
  const std::string path = std::string(DVSO_TEST_DATA_DIR) + "/../configs/labels_default.yaml";
  const labels::LabelRunOptions loaded = labels::LoadLabelRunOptions(path);
  labels::LabelRunOptions defaults;
  defaults.odometry = vo::OdometryOptions::Preset("default");
  EXPECT_EQ(labels::LabelRunOptionsToYaml(loaded), labels::LabelRunOptionsToYaml(defaults));
  EXPECT_EQ(loaded.labels.future_keyframes, 40);
  EXPECT_TRUE(loaded.labels.stereo_check.enabled);
}

TEST(PairCachingReader, ServesReadPairsOnceAndStaysBounded) {
  const auto sequence = OpenSequence(SimulatedSequenceDir());
  labels::PairCachingReader reader(*sequence, 4);
  EXPECT_EQ(reader.size(), sequence->size());
  SequenceReadOptions stereo;
  stereo.load_right = true;
  for (int i = 0; i < 3; ++i) reader.Read(i, stereo);
  EXPECT_EQ(reader.cached(), 3u);
  cv::Mat left, right;
  reader.Take(1, &left, &right);  // frames 0 and 1 are forgotten
  const StereoFrame direct = sequence->Read(1, stereo);
  EXPECT_EQ(cv::countNonZero(left != direct.left), 0);
  EXPECT_EQ(cv::countNonZero(right != direct.right), 0);
  EXPECT_EQ(reader.cached(), 1u);
  // Not cached (never read): read again from disk.
  reader.Take(10, &left, &right);
  EXPECT_EQ(cv::countNonZero(left != sequence->Read(10, stereo).left), 0);
  EXPECT_EQ(reader.cached(), 0u);
  // At most 4 pairs are held.
  for (int i = 11; i < 20; ++i) reader.Read(i, stereo);
  EXPECT_EQ(reader.cached(), 4u);
  reader.Take(12, &left, &right);  // dropped earlier: read again, still correct
  EXPECT_EQ(cv::countNonZero(right != sequence->Read(12, stereo).right), 0);
  EXPECT_EQ(reader.rereads(), 2);
  EXPECT_GT(reader.read_ms(), 0.0);
}
