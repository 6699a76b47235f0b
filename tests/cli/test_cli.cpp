// End-to-end checks of the `dvso` command line: usage errors and malformed
// input give one clear message and a non-zero exit, never a crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/disparity_io.h"
#include "core/fs_util.h"
#include "core/simulator.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace fs = std::filesystem;

namespace {

using dvso::testing::CliRun;
using dvso::testing::RunDvso;

std::string TempDir(const std::string& name) {
  return dvso::testing::ScratchDir("cli_" + name);
}

}  // namespace

TEST(Cli, HelpListsEverySubcommand) {
  const CliRun r = RunDvso("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* sub : {"demo", "simulate", "eval-odometry", "eval-depth", "odometry", "labels"}) {
    EXPECT_NE(r.out.find(sub), std::string::npos) << sub;
  }
}

TEST(Cli, UnknownSubcommandFails) {
  const CliRun r = RunDvso("frobnicate");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_EQ(r.out, "dvso: error: unknown subcommand 'frobnicate' (see dvso --help)\n");
}

// Command-line mistakes are one line like every other error (CLI11 alone prints two and exits 105-109),
// name the flag and the subcommand whose --help lists the options, and exit 2 (usage).
TEST(Cli, UsageErrorsAreOneLineNamingTheFlagAndExitTwo) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"odometry --mode foo --sequence s --out o", "--mode: foo not in"},
      {"odometry --out o", "--sequence is required"},
      {"odometry --sequence s --out o --no-such-flag", "--no-such-flag"},
      {"eval-odometry --gt a --est b --step x", "--step"},
      {"", "A subcommand is required"},
  };
  for (const auto& [args, expected] : cases) {
    const CliRun r = RunDvso(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.out;
    EXPECT_EQ(r.out.rfind("dvso: error: ", 0), 0u) << args << "\n" << r.out;
    EXPECT_NE(r.out.find(expected), std::string::npos) << args << "\n" << r.out;
    EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << args << ": not one line\n" << r.out;
  }
  EXPECT_NE(RunDvso("odometry --out o").out.find("(see dvso odometry --help)"), std::string::npos);
}

TEST(Cli, MissingTrajectoryFileIsOneClearError) {
  const std::string dir = TempDir("missing");
  const CliRun r = RunDvso("eval-odometry --gt " + dir + "/nope.txt --est " + dir + "/nope2.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("nope.txt"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("dvso: error:"), std::string::npos) << r.out;
}

TEST(Cli, OutOfRangeCameraValuesAreRejectedNotIgnored) {
  // 0 / -1 used to mean "not given" inside: `--virtual-baseline 0` silently took the model's b_v,
  // `simulate --cx -5` the KITTI principal point.
  const std::string dir = TempDir("baselines");
  std::ofstream(dir + "/gt.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"odometry --virtual-baseline 0 --mode dvso --sequence " + dir + " --out " + dir + "/o", "--virtual-baseline"},
      {"odometry --virtual-baseline -0.5 --mode dvso --sequence " + dir + " --out " + dir + "/o", "--virtual-baseline"},
      {"ablation --tuned-baseline -1 --sequence " + dir + " --gt " + dir + "/gt.txt", "--tuned-baseline"},
      {"simulate --cx -5 --out " + dir + "/o", "--cx"},
      {"simulate --baseline 0 --out " + dir + "/o", "--baseline"}};
  for (const auto& [args, option] : cases) {
    const CliRun r = RunDvso(args);
    EXPECT_NE(r.exit_code, 0) << args;
    EXPECT_NE(r.out.find(option + ": must be"), std::string::npos) << args << "\n" << r.out;
    EXPECT_FALSE(fs::exists(dir + "/o")) << args;
  }
}

// Options a layout or mode would silently ignore are errors: a camera file for a sequence with its
// own calibration, a right disparity folder outside dvso mode.
TEST(Cli, CameraFileForACalibratedLayoutAndPredictionsOutsideDvsoAreErrors) {
  const std::string dir = TempDir("ignored_options");
  std::ofstream(dir + "/calib.txt") << "P0: 700 0 300 0 0 700 100 0 0 0 1 0\nP1: 700 0 300 -350 0 700 100 0 0 0 1 0\n";
  std::ofstream(dir + "/camera.txt") << "Pinhole 700 700 300 100 0\n640 200\ncrop\n640 200\n";
  const CliRun camera = RunDvso("odometry --mode mono --sequence " + dir + " --camera " + dir + "/camera.txt --out " +
                                dir + "/o");
  EXPECT_EQ(camera.exit_code, 1) << camera.out;
  EXPECT_NE(camera.out.find("--camera FILE is for image folders only"), std::string::npos) << camera.out;
  const CliRun right = RunDvso("odometry --mode stereo --sequence " + dir + " --disparity-right " + dir + " --out " +
                               dir + "/o");
  EXPECT_EQ(right.exit_code, 1) << right.out;
  EXPECT_NE(right.out.find("need --mode dvso"), std::string::npos) << right.out;
  EXPECT_FALSE(fs::exists(dir + "/o"));
}

// A mono run whose camera never translates never initialises: the trajectory is written (one line per
// frame) but holds no estimate, which the run must say rather than look like a result.
TEST(Cli, MonoRunThatNeverInitialisesSaysSo) {
  const std::string dir = TempDir("never_initialises");
  fs::create_directories(dir + "/images");
  cv::Mat texture(200, 320, CV_8UC1);
  cv::randu(texture, 0, 255);
  for (int i = 0; i < 6; ++i) cv::imwrite(dir + "/images/" + std::to_string(100 + i) + ".png", texture);
  std::ofstream(dir + "/camera.txt") << "Pinhole 300 300 160 100 0\n320 200\n";
  const CliRun r = RunDvso("odometry --mode mono --no-progress --sequence " + dir + "/images --camera " + dir +
                           "/camera.txt --out " + dir + "/o");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: no frame was tracked (6 initializing"), std::string::npos) << r.out;
  EXPECT_TRUE(fs::exists(dir + "/o/trajectory.txt"));
}

// A stereo run whose every frame after the first is lost (images too small for its pyramid here) has only
// the first frame's origin in its trajectory: the same warning, although no frame was "initializing".
TEST(Cli, StereoRunThatLosesEveryFrameSaysSo) {
  const std::string dir = TempDir("stereo_all_lost");
  fs::create_directories(dir + "/image_0");
  fs::create_directories(dir + "/image_1");
  std::ofstream(dir + "/calib.txt") << "P0: 23 0 19.5 0 0 23 5.8 0 0 0 1 0\nP1: 23 0 19.5 -12.4 0 23 5.8 0 0 0 1 0\n";
  for (int i = 0; i < 5; ++i) {
    cv::Mat texture(12, 40, CV_8UC1);
    cv::randu(texture, 0, 255);
    cv::imwrite(dir + "/image_0/" + dvso::FrameFileName(i, ".png"), texture);
    cv::imwrite(dir + "/image_1/" + dvso::FrameFileName(i, ".png"), texture);
  }
  const CliRun r = RunDvso("odometry --mode stereo --no-progress --sequence " + dir + " --out " + dir + "/o");
  EXPECT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NE(r.out.find("lost 4"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("warning: no frame was tracked (0 initializing, 4 lost of 5)"), std::string::npos) << r.out;
}

TEST(Cli, RightGroundTruthWithoutRightLabelsIsAnError) {
  const std::string dir = TempDir("right_gt");
  const CliRun r = RunDvso("labels --sequence " + dir + " --out " + dir + "/l --gt-disparity-right " + dir);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("--right-labels"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/l"));
}

TEST(Cli, MalformedTrajectoryIsOneClearError) {
  const std::string dir = TempDir("malformed");
  std::ofstream(dir + "/gt.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::ofstream(dir + "/est.txt") << "1 0 0 0 0 1 0 0 0 0 1\n";  // 11 numbers
  const CliRun r = RunDvso("eval-odometry --gt " + dir + "/gt.txt --est " + dir + "/est.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("est.txt"), std::string::npos) << r.out;
}

TEST(Cli, EvalOdometryPlotDirThatIsAFileFailsBeforeAnyMetric) {
  const std::string dir = TempDir("plotfile");
  std::ofstream(dir + "/gt.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n";
  std::ofstream(dir + "/plots") << "a file\n";
  const CliRun r = RunDvso("eval-odometry --gt " + dir + "/gt.txt --est " + dir + "/gt.txt --plot-dir " + dir + "/plots");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("plots"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("t_rel"), std::string::npos) << r.out;  // no metrics printed first
}

TEST(Cli, OdometryOnMissingSequenceFailsCleanly) {
  const std::string dir = TempDir("noseq");
  const CliRun r = RunDvso("odometry --sequence " + dir + "/absent --mode stereo --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("absent"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/out/trajectory.txt"));
}

// `dvso labels --config C --preset P`: P is the base C's odometry keys change (as in `dvso odometry`); a C
// that names another preset contradicts P.
TEST(Cli, LabelsPresetIsTheBaseOfAConfigWithoutOne) {
  const std::string dir = dvso::testing::FreshSimulatedSequence("labels_preset", 3);
  ASSERT_FALSE(dir.empty());
  std::ofstream(dir + "/labels_only.yaml") << "labels:\n  max_depth: 50\n";
  const CliRun fast = RunDvso("labels --quiet --preset fast --config " + dir + "/labels_only.yaml --sequence " + dir +
                              "/seq --out " + dir + "/fast");
  ASSERT_EQ(fast.exit_code, 0) << fast.out;
  EXPECT_NE(fast.out.find("active_points: 800"), std::string::npos) << fast.out;  // the fast preset's
  EXPECT_NE(fast.out.find("max_depth: 50"), std::string::npos) << fast.out;
  std::ofstream(dir + "/named.yaml") << "preset: default\nlabels:\n  max_depth: 50\n";
  const CliRun contradiction = RunDvso("labels --quiet --preset fast --config " + dir + "/named.yaml --sequence " +
                                       dir + "/seq --out " + dir + "/named");
  EXPECT_EQ(contradiction.exit_code, 1);
  EXPECT_NE(contradiction.out.find("named.yaml"), std::string::npos) << contradiction.out;
  EXPECT_NE(contradiction.out.find("--preset fast"), std::string::npos) << contradiction.out;
}

TEST(Cli, EvalLabelsCountsWrongLabelsByPlaceAndNamesAMissingGroundTruth) {
  const std::string dir = TempDir("eval_labels");
  fs::create_directories(dir + "/labels");
  fs::create_directories(dir + "/gt");
  cv::Mat gt(10, 40, CV_32F, cv::Scalar(10.f));
  gt.colRange(20, 23).setTo(20.f);  // a 3 px pole
  cv::Mat labels(10, 40, CV_32F, cv::Scalar(0.f));
  labels.at<float>(5, 21) = 12.f;  // on the pole, wrong by 8 px
  labels.at<float>(5, 5) = 10.25f;  // open background, right
  dvso::WriteKittiMapPng(dir + "/labels/000000.png", labels);
  dvso::WriteKittiMapPng(dir + "/gt/000000.png", gt);
  const CliRun r = RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out.substr(r.out.find('{')));
  EXPECT_EQ(j["compared_labels"].get<int>(), 2);
  EXPECT_DOUBLE_EQ(j["share_within_1px"].get<double>(), 0.5);
  EXPECT_EQ(j["by_kind"]["thin"]["wrong"].get<int>(), 1);
  EXPECT_EQ(j["by_kind"]["other"]["labels"].get<int>(), 1);
  EXPECT_EQ(j["by_kind"]["other"]["wrong"].get<int>(), 0);

  // The temporary file of a killed writer is no label map (dvso labels removes it when it resumes).
  std::ofstream(dir + "/labels/000002.tmp-writing.png") << "half a PNG";
  const CliRun leftover = RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt --json");
  ASSERT_EQ(leftover.exit_code, 0) << leftover.out;
  EXPECT_EQ(nlohmann::json::parse(leftover.out.substr(leftover.out.find('{')))["compared_labels"].get<int>(), 2);
  fs::remove(dir + "/labels/000002.tmp-writing.png");

  dvso::WriteKittiMapPng(dir + "/labels/000001.png", labels);  // no GT for this one
  const CliRun missing = RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt");
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.out.find("000001.png"), std::string::npos) << missing.out;

  // A missing image is the same one-line error (no OpenCV warning before it), a missing folder too.
  fs::remove(dir + "/labels/000001.png");
  fs::create_directories(dir + "/images");
  const CliRun no_image = RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt --images " + dir + "/images");
  EXPECT_EQ(no_image.exit_code, 1);
  EXPECT_NE(no_image.out.find("images/000000.png"), std::string::npos) << no_image.out;
  EXPECT_EQ(no_image.out.find("WARN"), std::string::npos) << no_image.out;
  const CliRun no_folder = RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt --images " + dir + "/nope");
  EXPECT_EQ(no_folder.exit_code, 1);
  EXPECT_NE(no_folder.out.find("nope"), std::string::npos) << no_folder.out;

  // Pictures of the labels on the images (wrong labels red).
  cv::imwrite(dir + "/images/000000.png", cv::Mat(10, 40, CV_8UC1, cv::Scalar(90)));
  const CliRun pictures = RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt --images " + dir +
                                  "/images --pictures " + dir + "/pictures");
  ASSERT_EQ(pictures.exit_code, 0) << pictures.out;
  const cv::Mat picture = cv::imread(dir + "/pictures/000000.png");
  ASSERT_FALSE(picture.empty());
  EXPECT_EQ(picture.at<cv::Vec3b>(5, 21), cv::Vec3b(0, 0, 255));  // the wrong label on the pole
  EXPECT_NE(RunDvso("eval-labels --labels " + dir + "/labels --gt " + dir + "/gt --pictures " + dir + "/p2").exit_code, 0);
}

TEST(Cli, ShorterSimulationIntoTheSameFolderLeavesNoStaleFrames) {
  const std::string dir = TempDir("resimulate");
  const std::string common = "simulate --quiet --width 96 --height 32 --out " + dir + "/seq";
  ASSERT_EQ(RunDvso(common + " --count 6 --color").exit_code, 0);
  const CliRun again = RunDvso(common + " --count 3");
  ASSERT_EQ(again.exit_code, 0) << again.out;
  auto count = [](const std::string& folder) {
    if (!fs::is_directory(folder)) return 0;
    int n = 0;
    for (const auto& entry : fs::directory_iterator(folder)) n += entry.path().extension() == ".png";
    return n;
  };
  EXPECT_EQ(count(dir + "/seq/image_0"), 3);
  EXPECT_EQ(count(dir + "/seq/disp_1"), 3);
  EXPECT_EQ(count(dir + "/seq/image_2"), 0);  // the earlier colour frames are not this grey sequence's
  // ... so the folder reads as one consistent sequence again.
  const CliRun odometry = RunDvso("odometry --no-progress --mode stereo --preset fast --sequence " + dir + "/seq --out " +
                                  dir + "/out --first 1 --count 2147483647");
  ASSERT_EQ(odometry.exit_code, 0) << odometry.out;
  // A huge --count means "to the end" (2 frames from frame 1), not an overflowed empty range.
  std::ifstream trajectory(dir + "/out/trajectory.txt");
  int lines = 0;
  for (std::string line; std::getline(trajectory, line);) lines += !line.empty();
  EXPECT_EQ(lines, 2);
}

TEST(Cli, LabelListWithTwoSequencesOfOneNameIsAnError) {
  const std::string dir = TempDir("label_list");
  fs::create_directories(dir + "/a/seq");
  fs::create_directories(dir + "/b/seq");
  std::ofstream(dir + "/list.txt") << dir << "/a/seq\n" << dir << "/b/seq/\n";
  const CliRun r = RunDvso("labels --list " + dir + "/list.txt --out " + dir + "/labels");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("distinct names"), std::string::npos) << r.out;
}

// Options that another option would silently override or ignore are errors, like --exposure-level with
// --appearance varied: the varied look raises a smaller height jitter to its minimum, a switched-off effect
// has no strength, and a trajectory file sets the speed.
TEST(Cli, SimulateRejectsOptionsThatWouldBeOverriddenOrIgnored) {
  const std::string dir = TempDir("simulate_ignored");
  std::ofstream(dir + "/poses.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1 1\n";
  const std::string common = "simulate --quiet --count 1 --width 96 --height 32 --texture-size 64 --out " + dir + "/o";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" --appearance varied --height-jitter 0.02", "--height-jitter"},
      {" --no-noise --noise-sigma 2", "--noise-sigma"},
      {" --no-vignetting --vignetting 0.2", "--vignetting"},
      {" --no-vignetting --right-vignetting 0", "--right-vignetting"},
      {" --no-exposure-drift --exposure-sigma 0.05", "--exposure-sigma"},
      {" --trajectory " + dir + "/poses.txt --speed 5", "--speed"}};
  for (const auto& [args, option] : cases) {
    const CliRun r = RunDvso(common + args);
    EXPECT_EQ(r.exit_code, 1) << args << "\n" << r.out;
    EXPECT_NE(r.out.find("dvso: error: " + option), std::string::npos) << args << "\n" << r.out;
    EXPECT_FALSE(fs::exists(dir + "/o")) << args << ": refused before writing";
  }
  // Each of them alone (or with the effect on, the look fixed, the path generated) still acts.
  const CliRun alone = RunDvso(common + " --height-jitter 0.02 --camera-height 1.5 --noise-sigma 2 --vignetting 0.2 "
                                        "--exposure-sigma 0.05 --speed 5");
  EXPECT_EQ(alone.exit_code, 0) << alone.out;
  // With the varied look a camera height is the look's centre and a jitter of at least its minimum is used
  // as given: both act.
  const CliRun varied = RunDvso(common + " --appearance varied --camera-height 1.5 --height-jitter 0.05");
  EXPECT_EQ(varied.exit_code, 0) << varied.out;
}

// Scripts that cache rendered worlds compare the simulator's world version (`dvso --version`) with the one a
// world's simulation.yaml records; every version stays renderable with --world-version.
TEST(Cli, VersionNamesTheSimulatorWorldVersionThatSimulationYamlRecords) {
  const CliRun version = RunDvso("--version");
  EXPECT_EQ(version.exit_code, 0);
  const std::string current = std::to_string(dvso::kSimulatorWorldVersion);
  EXPECT_NE(version.out.find("simulator world version " + current + ")"), std::string::npos) << version.out;
  const std::string dir = TempDir("world_version");
  auto recorded = [&](const std::string& args) {
    const CliRun r = RunDvso("simulate --quiet --count 1 --width 64 --height 32 --texture-size 64 --out " + dir +
                             "/seq " + args);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    std::ifstream yaml(dir + "/seq/simulation.yaml");
    std::string line, value;
    while (std::getline(yaml, line)) {
      if (line.rfind("world_version: ", 0) == 0) value = line.substr(15);
    }
    std::filesystem::remove_all(dir + "/seq");
    return value;
  };
  EXPECT_EQ(recorded(""), current);
  EXPECT_EQ(recorded("--world-version 1"), "1");
  for (const int wrong : {0, dvso::kSimulatorWorldVersion + 1}) {
    const CliRun r = RunDvso("simulate --quiet --count 1 --out " + dir + "/seq --world-version " + std::to_string(wrong));
    EXPECT_EQ(r.exit_code, 1) << r.out;
    EXPECT_NE(r.out.find("--world-version must be in [1, " + current + "]"), std::string::npos) << r.out;
  }
}
