// Training: a tiny network overfits one batch; a few CPU steps on simulator
// data through the full Trainer (stages, checkpoints, logs); exact resume;
// config strictness and the learning-rate schedule.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <nlohmann/json.hpp>
#include <vector>

#include "core/error.h"
#include "stacknet/config.h"
#include "stacknet/data_loader.h"
#include "stacknet/dataset.h"
#include "stacknet/export.h"
#include "stacknet/trainer.h"
#include "stacknet_test_util.h"
#include "tests/temp_dir.h"

namespace dvso::stacknet {
namespace {
namespace fs = std::filesystem;

std::string TempDir(const std::string& name) {
  return dvso::testing::ScratchDir("stacknet_" + name);
}

TEST(Training, TinyNetworkOverfitsOneBatch) {
  at::set_num_threads(1);
  torch::manual_seed(5);
  StackNet net(testing::TinyNetwork());
  StageOptions stage;
  stage.model = "simple";
  stage.learning_rate = 2e-3;
  torch::optim::Adam optimizer(PrepareStage(net, stage), torch::optim::AdamOptions(stage.learning_rate));
  const StereoBatch batch = testing::SyntheticBatch(2, 32, 64, 4, 11);
  const double first = TrainStep(net, optimizer, stage, LossOptions{}, batch).total.item<double>();
  double last = first;
  for (int step = 0; step < 150; ++step) last = TrainStep(net, optimizer, stage, LossOptions{}, batch).total.item<double>();
  EXPECT_LT(last, first / 5.0) << "first " << first << " last " << last;
}

TEST(Config, StageNamesCannotBreakTheLossCsv) {
  StageOptions stage;
  stage.model = "simple";
  stage.name = "simple_Ko";
  EXPECT_NO_THROW(stage.Check());
  stage.name = "simple,Ko";  // a resume reads losses.csv back by comma
  EXPECT_THROW(stage.Check(), Error);
}

TEST(Config, UnknownKeysAreErrorsAndYamlRoundTrips) {
  EXPECT_THROW(ParseConfig("network: {encoder_depht: 18}\n", "x.yaml", false), Error);
  EXPECT_THROW(ParseConfig("netwrk: {}\n", "x.yaml", false), Error);
  EXPECT_THROW(ParseConfig("stages: [{name: a, epochz: 3}]\n", "x.yaml", false), Error);
  EXPECT_THROW(ParseConfig("network: {encoder_depth: 19}\ndata: {sequences: [a]}\nstages: [{}]\n"), Error);
  const StackNetConfig paper = LoadConfig(std::string(DVSO_TEST_DATA_DIR) + "/../configs/stacknet_paper.yaml");
  EXPECT_EQ(paper.network.encoder_depth, 50);
  EXPECT_EQ(paper.network.input_width, 512);
  EXPECT_EQ(paper.stages.size(), 6u);
  EXPECT_EQ(paper.stages[3].model, "stack");
  EXPECT_FALSE(paper.stages[1].use_supervised);
  EXPECT_FALSE(paper.stages[2].use_unsupervised);
  EXPECT_EQ(ConfigToYaml(ParseConfig(ConfigToYaml(paper))), ConfigToYaml(paper));
  // Paper 5.1: 1e-4 for 50 epochs, then halved every 15 epochs.
  EXPECT_DOUBLE_EQ(paper.stages[0].LearningRateAt(49), 1e-4);
  EXPECT_DOUBLE_EQ(paper.stages[0].LearningRateAt(50), 5e-5);
  EXPECT_DOUBLE_EQ(paper.stages[0].LearningRateAt(64), 5e-5);
  EXPECT_DOUBLE_EQ(paper.stages[0].LearningRateAt(65), 2.5e-5);
  EXPECT_DOUBLE_EQ(paper.stages[1].LearningRateAt(39), 5e-5);
}

TEST(Config, EveryShippedStackNetConfigLoadsAndChecks) {
  // A typo or a stage pointing at an undefined dataset in a committed config would only surface
  // when someone starts an hour-long training run.
  int loaded = 0;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(DVSO_TEST_DATA_DIR) + "/../configs")) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("stacknet_", 0) != 0 || entry.path().extension() != ".yaml") continue;
    SCOPED_TRACE(name);
    // Configs meant for `dvso train --sequence DIR` leave data.sequences to the command line.
    StackNetConfig config = LoadConfig(entry.path().string(), false);
    if (config.data.sequences.empty() && config.data.split_file.empty()) config.data.sequences = {"given/on/the/cli"};
    EXPECT_NO_THROW(config.Check());
    ++loaded;
  }
  EXPECT_GE(loaded, 6);
}

// `dvso train --sequence DIR` replaces the default data; where every stage names a dataset (the shipped
// configs but the tiny one) the stages would never read DIR, and the export would still take its camera.
TEST(Config, SequenceOptionNeedsAStageOnTheDefaultData) {
  const std::string datasets = "datasets: {K_o: {sequences: [a]}, K_r: {sequences: [b]}}\n";
  StackNetConfig named =
      ParseConfig(datasets + "stages: [{name: s0, data: K_o}, {name: s1, data: K_r}, {name: s2, data: K_o}]\n",
                  "named.yaml", false);
  try {
    SetDefaultSequences(&named, {"mine"});
    ADD_FAILURE() << "--sequence accepted where no stage trains on the default data";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("--sequence"), std::string::npos) << message;
    EXPECT_NE(message.find("'K_o', 'K_r'"), std::string::npos) << message;
  }
  EXPECT_TRUE(named.data.sequences.empty());
  StackNetConfig paper = LoadConfig(std::string(DVSO_TEST_DATA_DIR) + "/../configs/stacknet_paper.yaml", false);
  EXPECT_THROW(SetDefaultSequences(&paper, {"mine"}), Error);

  // One stage on the default data is enough; the sequences then replace a default split (which would win).
  StackNetConfig mixed = ParseConfig(
      datasets + "data: {split_file: s.txt}\nstages: [{name: s0, data: K_o}, {name: s1}]\n", "mixed.yaml", false);
  SetDefaultSequences(&mixed, {"mine"});
  EXPECT_EQ(mixed.data.sequences, std::vector<std::string>{"mine"});
  EXPECT_TRUE(mixed.data.split_file.empty());
  EXPECT_NO_THROW(mixed.Check());
}

// yaml-cpp reads `key:` and `key: ~` as the string "null": `output_dir:` trained into a folder named null.
TEST(Config, KeysWithoutAValueAreErrors) {
  auto error_of = [](const std::string& yaml) {
    try {
      ParseConfig(yaml, "x.yaml", false);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  for (const auto& [yaml, key] : std::vector<std::pair<std::string, std::string>>{
           {"train:\n  output_dir:\n", "train.output_dir"},
           {"train: {output_dir: ~}\n", "train.output_dir"},
           {"network: {encoder_depth: null}\n", "network.encoder_depth"},
           {"data: {sequences: }\n", "data.sequences"},
           {"datasets: {K: {split_file: }}\n", "datasets.K.split_file"},
           {"stages: [{name: a, data: }]\n", "stages[0].data"}}) {
    const std::string message = error_of(yaml);
    EXPECT_NE(message.find(key + ": has no value"), std::string::npos) << yaml << " -> '" << message << "'";
    EXPECT_NE(message.find("x.yaml"), std::string::npos) << message;
  }
  // An empty string is a value ('' = none for the label folders).
  EXPECT_EQ(error_of("data: {label_dir_left: ''}\n"), "");
  EXPECT_EQ(ParseConfig("data: {label_dir_left: ''}\n", "x.yaml", false).data.label_dir_left, "");
}

// A split lists its frames itself: frame_step beside it would be ignored by the dataset.
TEST(Config, FrameStepWithASplitFileIsAnError) {
  EXPECT_NO_THROW(ParseConfig("data: {split_file: s.txt, frame_step: 1}\nstages: [{}]\n"));
  EXPECT_NO_THROW(ParseConfig("data: {sequences: [a], frame_step: 2}\nstages: [{}]\n"));
  try {
    ParseConfig("data: {split_file: s.txt, frame_step: 2}\nstages: [{}]\n", "x.yaml");
    ADD_FAILURE() << "frame_step accepted beside split_file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("frame_step"), std::string::npos) << e.what();
  }
  // A named dataset inherits data.frame_step; the error names the dataset.
  try {
    ParseConfig("data: {sequences: [a], frame_step: 2}\ndatasets: {K: {split_file: s.txt}}\nstages: [{data: K}]\n");
    ADD_FAILURE() << "an inherited frame_step accepted beside split_file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("datasets.K"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("frame_step"), std::string::npos) << e.what();
  }
}

void WriteText(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

// The error message of loading `path` ("" when it loads).
std::string LoadError(const std::string& path) {
  try {
    LoadConfig(path, false);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Config, BaseFileIsLaidUnderKeyByKey) {
  const std::string dir = TempDir("config_base");
  fs::create_directories(dir + "/sub");
  WriteText(dir + "/root.yaml",
            "network: {encoder_depth: 18, width_multiplier: 0.5}\n"
            "loss: {alpha_s: 3.0}\n"
            "train: {batch_size: 3}\n"
            "datasets: {A: {sequences: [a1, a2], label_dir_left: labels}, B: {sequences: [b]}}\n"
            "stages: [{name: s0, data: A, epochs: 2}, {name: s1, data: B, epochs: 1}]\n");
  // The base path is relative to the file that names it; the middle file has a base of its own.
  WriteText(dir + "/sub/middle.yaml", "base: ../root.yaml\nnetwork: {width_multiplier: 0.25}\n");
  WriteText(dir + "/sub/leaf.yaml",
            "base: middle.yaml\n"
            "train:\n"  // an empty section keeps the base's (it does not reset it to the defaults)
            "datasets: {A: {label_dir_left: ''}}\n"
            "stages: [{name: only, data: B, epochs: 5}]\n");
  const StackNetConfig leaf = LoadConfig(dir + "/sub/leaf.yaml", false);
  EXPECT_EQ(leaf.network.encoder_depth, 18);              // from the root
  EXPECT_DOUBLE_EQ(leaf.network.width_multiplier, 0.25);  // the middle file overrides one key of the map
  EXPECT_DOUBLE_EQ(leaf.loss.alpha_s, 3.0);
  EXPECT_EQ(leaf.train.batch_size, 3);
  ASSERT_EQ(leaf.datasets.size(), 2u);
  EXPECT_EQ(leaf.datasets[0].first, "A");
  EXPECT_EQ(leaf.datasets[0].second.sequences, (std::vector<std::string>{"a1", "a2"}));  // kept
  EXPECT_EQ(leaf.datasets[0].second.label_dir_left, "");                                  // overridden
  ASSERT_EQ(leaf.stages.size(), 1u);  // a list replaces the base's list whole
  EXPECT_EQ(leaf.stages[0].name, "only");
  EXPECT_EQ(leaf.stages[0].epochs, 5);

  // Unknown keys stay errors wherever they are, named with the file they are in; cycles and
  // missing bases are one-line errors.
  WriteText(dir + "/typo.yaml", "base: root.yaml\nnetwork: {widht_multiplier: 1}\n");
  EXPECT_NE(LoadError(dir + "/typo.yaml").find("widht_multiplier"), std::string::npos) << LoadError(dir + "/typo.yaml");
  WriteText(dir + "/bad_base.yaml", "loss: {alpha_ss: 1}\n");
  WriteText(dir + "/uses_bad_base.yaml", "base: bad_base.yaml\n");
  const std::string bad_base = LoadError(dir + "/uses_bad_base.yaml");
  EXPECT_NE(bad_base.find("alpha_ss"), std::string::npos) << bad_base;
  EXPECT_NE(bad_base.find("bad_base.yaml"), std::string::npos) << bad_base;
  WriteText(dir + "/cycle_a.yaml", "base: cycle_b.yaml\n");
  WriteText(dir + "/cycle_b.yaml", "base: cycle_a.yaml\n");
  EXPECT_NE(LoadError(dir + "/cycle_a.yaml").find("a cycle?"), std::string::npos) << LoadError(dir + "/cycle_a.yaml");
  WriteText(dir + "/missing.yaml", "base: nowhere.yaml\n");
  EXPECT_NE(LoadError(dir + "/missing.yaml").find("nowhere.yaml"), std::string::npos);
  // From text there is no file to be relative to.
  try {
    ParseConfig("base: root.yaml\n", "text", false);
    ADD_FAILURE() << "base: accepted in text";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("only when a config is loaded from a file"), std::string::npos) << e.what();
  }
}

// The ablation and experiment configs state only what they change; this pins that what they
// change is what their comments say (a stale copy once trained the ablations without GroupNorm).
// Each expectation is the shipped config with exactly the stated fields edited.
TEST(Config, AblationConfigsDifferFromTheShippedOneOnlyWhereTheySay) {
  const std::string configs = std::string(DVSO_TEST_DATA_DIR) + "/../configs/";
  const StackNetConfig main = LoadConfig(configs + "stacknet_cpu_main.yaml", false);
  ASSERT_EQ(main.datasets.size(), 2u);
  ASSERT_EQ(main.datasets[0].first, "K_o");

  StackNetConfig gt = main;  // K_o (and the default data) on 2 % GT samples of both views instead of labels
  gt.train.output_dir = "runs/stacknet_cpu_main_gt";
  for (DataOptions* d : {&gt.data, &gt.datasets[0].second}) {
    d->label_dir_left = "";
    d->gt_disparity_left = "disp_0";
    d->gt_disparity_right = "disp_1";
    d->gt_sample_fraction = 0.02;
  }
  EXPECT_EQ(ConfigToYaml(LoadConfig(configs + "stacknet_cpu_main_gt.yaml", false)), ConfigToYaml(gt));

  StackNetConfig self = main;  // no labels anywhere: no L_S in any stage
  self.train.output_dir = "runs/stacknet_cpu_main_self";
  self.data.label_dir_left = "";
  self.datasets[0].second.label_dir_left = "";
  EXPECT_EQ(ConfigToYaml(LoadConfig(configs + "stacknet_cpu_main_self.yaml", false)), ConfigToYaml(self));

  // v4: other worlds (paths checked by their count) and one more SimpleNet epoch.
  const StackNetConfig v4 = LoadConfig(configs + "stacknet_cpu_v4.yaml", false);
  EXPECT_EQ(v4.data.sequences.size(), 64u);
  EXPECT_EQ(v4.datasets.at(0).second.sequences.size(), 64u);
  EXPECT_EQ(v4.datasets.at(1).second.sequences.size(), 8u);
  StackNetConfig expected_v4 = main;
  expected_v4.train.output_dir = "runs/stacknet_cpu_v4";
  expected_v4.data.sequences = v4.data.sequences;
  expected_v4.datasets[0].second.sequences = v4.datasets[0].second.sequences;
  expected_v4.datasets[1].second.sequences = v4.datasets[1].second.sequences;
  expected_v4.stages[0].epochs = main.stages[0].epochs + 1;
  expected_v4.stages[0].lr_halving_start = main.stages[0].lr_halving_start + 1;
  EXPECT_EQ(ConfigToYaml(v4), ConfigToYaml(expected_v4));

  // v4_long (the shipped model's): v4 plus a second semi-supervised SimpleNet stage, StackNet at 5e-5.
  const StackNetConfig v4_long = LoadConfig(configs + "stacknet_cpu_v4_long.yaml", false);
  StackNetConfig expected_long = v4;
  expected_long.train.output_dir = "runs/stacknet_cpu_v4_long";
  StageOptions more = v4.stages[0];
  more.name = "simple_Ko_semi_more";
  more.epochs = 7;
  more.learning_rate = 1e-4;
  more.lr_halving_start = 4;
  expected_long.stages.insert(expected_long.stages.begin() + 1, more);
  ASSERT_EQ(expected_long.stages[4].name, "stack_Ko_semi");
  expected_long.stages[4].learning_rate = 5e-5;
  EXPECT_EQ(ConfigToYaml(v4_long), ConfigToYaml(expected_long));

  // Table 1, mid-length: v4's first stage alone for 4 epochs (its LR halving starts later), with
  // labels (semi) and without labels and L_S (self); nothing else differs between the two arms.
  StackNetConfig expected_semi = v4;
  expected_semi.train.output_dir = "runs/stacknet_cpu_v4_table1_semi";
  expected_semi.stages.resize(1);
  expected_semi.stages[0].epochs = 4;
  expected_semi.stages[0].lr_halving_start = -1;
  expected_semi.stages[0].lr_halving_every = 0;
  EXPECT_EQ(ConfigToYaml(LoadConfig(configs + "stacknet_cpu_v4_table1_semi.yaml", false)), ConfigToYaml(expected_semi));
  StackNetConfig expected_self = expected_semi;
  expected_self.train.output_dir = "runs/stacknet_cpu_v4_table1_self";
  expected_self.data.label_dir_left = "";
  expected_self.datasets[0].second.label_dir_left = "";
  expected_self.stages[0].name = "simple_Ko_self";
  expected_self.stages[0].use_supervised = false;
  EXPECT_EQ(ConfigToYaml(LoadConfig(configs + "stacknet_cpu_v4_table1_self.yaml", false)), ConfigToYaml(expected_self));
}

TEST(Data, SparseLabelsKeepTheirValuesScaledWithTheWidth) {
  cv::Mat sparse = cv::Mat::zeros(4, 8, CV_32F);
  sparse.at<float>(1, 5) = 10.0f;
  const cv::Mat half = ResizeSparseDisparity(sparse, 4, 2);
  EXPECT_EQ(cv::countNonZero(half), 1);
  EXPECT_FLOAT_EQ(half.at<float>(0, 2), 5.0f);
}

TEST(Data, EpochOrderIsAPermutationThatDependsOnEpoch) {
  auto a = EpochOrder(50, 1, 0, 0);
  auto b = EpochOrder(50, 1, 0, 1);
  EXPECT_NE(a, b);
  EXPECT_EQ(a, EpochOrder(50, 1, 0, 0));
  std::sort(a.begin(), a.end());
  for (int i = 0; i < 50; ++i) EXPECT_EQ(a[i], i);
}

// A monodepth split over a simulated KITTI raw drive: lines pick frames by their file
// number, side 'r' is the mirrored pair (FlipAndSwap), the colour pair 02/03 is read,
// and a frame the drive does not have is an error naming the split file.
TEST(Data, SplitFileOverARawDriveReadsTheNamedFramesAndSides) {
  const std::string dir = TempDir("split");
  const std::string sim = std::string(DVSO_BINARY) + " simulate --quiet --out " + dir +
                          "/seq --count 6 --width 128 --height 64 --color --raw-layout sync > /dev/null 2>&1";
  ASSERT_EQ(std::system(sim.c_str()), 0) << sim;
  const std::string drive = "2011_09_26/2011_09_26_drive_0001_sync";
  std::ofstream(dir + "/split.txt") << "# two sides of frame 4, then frame 1\n"
                                    << drive << " 0000000004 l\n" << drive << " 0000000004 r\n" << drive << " 1 l\n";
  StackNetConfig config = LoadConfig(std::string(DVSO_TEST_DATA_DIR) + "/../configs/stacknet_tiny.yaml", false);
  config.data.sequences = {dir + "/seq"};
  const StereoDataset odometry_layout(config.data, 64, 32);
  config.data.sequences.clear();
  config.data.split_file = dir + "/split.txt";
  config.data.split_root = dir + "/seq/kitti_raw";
  const StereoDataset split(config.data, 64, 32);
  ASSERT_EQ(split.size(), 3);
  const StereoSample reference4 = odometry_layout.Load(4), reference1 = odometry_layout.Load(1);
  const StereoSample left4 = split.Load(0), right4 = split.Load(1), left1 = split.Load(2);
  EXPECT_TRUE(torch::equal(left4.left, reference4.left));  // colour camera 02 = the simulator's image_2
  EXPECT_TRUE(torch::equal(left4.right, reference4.right));
  EXPECT_TRUE(torch::equal(left1.left, reference1.left));
  EXPECT_FALSE(torch::equal(left1.left, reference4.left));
  EXPECT_TRUE(torch::equal(right4.left, reference4.right.flip({2})));
  EXPECT_TRUE(torch::equal(right4.right, reference4.left.flip({2})));
  EXPECT_GT(reference4.left.std().item<double>(), 0.01);

  std::ofstream(dir + "/missing.txt") << drive << " 0000000004 l\n" << drive << " 0000000017 l\n";
  config.data.split_file = dir + "/missing.txt";
  try {
    StereoDataset bad(config.data, 64, 32);
    ADD_FAILURE() << "a frame the drive does not have was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.txt"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("0000000017"), std::string::npos) << e.what();
  }
}

class SimulatedTraining : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sequence_ = TempDir("sim") + "/seq";
    const std::string command = std::string(DVSO_BINARY) + " simulate --out " + sequence_ +
                                " --count 8 --width 128 --height 64 --color > /dev/null 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
  }
  StackNetConfig TinyConfig(const std::string& output_dir) const {
    StackNetConfig config = LoadConfig(std::string(DVSO_TEST_DATA_DIR) + "/../configs/stacknet_tiny.yaml", false);
    config.data.sequences = {sequence_};
    config.train.output_dir = output_dir;
    config.Check();
    return config;
  }
  // The resume tests' schedule: stage 0 in two epochs of 3 steps, one thread (bit-exact reruns).
  StackNetConfig ResumeConfig(const std::string& output_dir) const {
    StackNetConfig config = TinyConfig(output_dir);
    config.stages[0].max_steps_per_epoch = 3;
    config.stages[0].epochs = 2;
    config.train.num_threads = 1;
    return config;
  }
  // A run of `config` stopped (as by Ctrl-C) once it reaches global step `step`.
  static TrainResult RunUntilStep(const StackNetConfig& config, int64_t step) {
    Trainer trainer(config, [step](const TrainingPosition& p) { return p.global_step == step; });
    return trainer.Run();
  }
  static std::string sequence_;
};
std::string SimulatedTraining::sequence_;

TEST_F(SimulatedTraining, DatasetReadsPairsAndSparseGtLabels) {
  const StackNetConfig config = TinyConfig(TempDir("data"));
  const StereoDataset dataset(config.data, 64, 32);
  ASSERT_EQ(dataset.size(), 8);
  const StereoSample s = dataset.Load(3);
  EXPECT_EQ(s.left.sizes(), (std::vector<int64_t>{3, 32, 64}));
  EXPECT_GT(s.left.max().item<double>(), 0.0);
  EXPECT_LE(s.left.max().item<double>(), 1.0);
  const double labelled = s.left_mask.mean().item<double>();
  EXPECT_GT(labelled, 0.0);
  EXPECT_LT(labelled, 0.2);  // sparse
  EXPECT_GT(s.right_mask.sum().item<double>(), 0.0);
  // Labels are width fractions of plausible disparities.
  const torch::Tensor values = s.left_label.masked_select(s.left_mask > 0);
  EXPECT_GT(values.min().item<double>(), 0.0);
  EXPECT_LT(values.max().item<double>(), 0.5);
}

TEST(Data, LabelsOfAnotherCameraPairAreRefused) {
  const std::string dir = TempDir("label_pair");
  fs::create_directories(dir + "/labels/right");
  // Hand-made labels (no summary) and summaries from before labels named their pair are not checked.
  EXPECT_NO_THROW(RequireLabelsOfTrainingPair(dir + "/labels", CameraPair::kColour));
  std::ofstream(dir + "/labels/labels_summary.json") << "{\"sequence\": \"s\"}";
  EXPECT_NO_THROW(RequireLabelsOfTrainingPair(dir + "/labels", CameraPair::kColour));
  std::ofstream(dir + "/labels/labels_summary.json") << "{\"sequence\": \"s\", \"cameras\": \"grey\"}";
  EXPECT_NO_THROW(RequireLabelsOfTrainingPair(dir + "/labels", CameraPair::kGrey));
  EXPECT_NO_THROW(RequireLabelsOfTrainingPair(dir + "/labels/right", CameraPair::kGrey));  // summary one up
  for (const std::string& labels : {dir + "/labels", dir + "/labels/right"}) {
    try {
      RequireLabelsOfTrainingPair(labels, CameraPair::kColour);  // a raw drive: training reads 02/03
      ADD_FAILURE() << "grey labels accepted for colour training: " << labels;
    } catch (const Error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("labels_summary.json"), std::string::npos) << what;
      EXPECT_NE(what.find("dvso labels --cameras colour"), std::string::npos) << what;
    }
  }
  EXPECT_THROW(RequireLabelsOfTrainingPair(dir + "/labels/right/", CameraPair::kColour), Error);  // trailing slash
  EXPECT_EQ(TrainingCameraPair(dir), CameraPair::kGrey);  // not a raw drive
}

TEST_F(SimulatedTraining, DatasetRefusesLabelsOfAnotherPair) {
  // The sequence is in the odometry layout: training reads its grey pair, so colour labels are refused.
  const std::string labels = TempDir("pair_labels") + "/labels";
  fs::create_directories(labels);
  std::ofstream(labels + "/labels_summary.json") << "{\"cameras\": \"colour\"}";
  StackNetConfig config = TinyConfig(TempDir("pair_data"));
  config.data.label_dir_left = labels;
  EXPECT_THROW(StereoDataset(config.data, 64, 32), Error);
  std::ofstream(labels + "/labels_summary.json") << "{\"cameras\": \"grey\"}";
  EXPECT_NO_THROW(StereoDataset(config.data, 64, 32));
}

TEST_F(SimulatedTraining, FewCpuStepsThroughAllStagesWriteCheckpointsAndLogs) {
  const std::string out = TempDir("train");
  Trainer trainer(TinyConfig(out));
  trainer.set_config_name("stacknet_tiny");
  const TrainResult result = trainer.Run();
  EXPECT_TRUE(result.finished);
  EXPECT_EQ(result.position.global_step, 4);  // 2 stages x 2 steps
  EXPECT_TRUE(std::isfinite(result.last_loss));
  for (const char* file : {"checkpoint_final.pt", "checkpoint_last.pt", "checkpoint_stage0_simple_semi.pt",
                           "checkpoint_stage1_stack_semi.pt", "losses.csv", "epochs.jsonl", "config.yaml"}) {
    EXPECT_TRUE(fs::exists(out + "/" + file)) << file;
  }
  std::ifstream csv(out + "/losses.csv");
  int lines = 0;
  for (std::string line; std::getline(csv, line);) ++lines;
  EXPECT_EQ(lines, 5);  // header + 4 steps
  EXPECT_EQ(ReadCheckpointInfo(out + "/checkpoint_final.pt").trained_model, "stack");
  EXPECT_EQ(ReadCheckpointInfo(out + "/checkpoint_stage0_simple_semi.pt").trained_model, "simple");
  // Every checkpoint names its config, so `dvso export` can write it into the model's metadata.
  EXPECT_EQ(ReadCheckpointInfo(out + "/checkpoint_stage0_simple_semi.pt").config_name, "stacknet_tiny");
  EXPECT_EQ(ReadCheckpointInfo(out + "/checkpoint_final.pt").config_name, "stacknet_tiny");
}

TEST_F(SimulatedTraining, InitFromStartsFromTheWeightsOfAnExportedModel) {
  // A source network, trained a few steps and exported as users get it from `dvso export`.
  const std::string source_dir = TempDir("init_source");
  Trainer source(TinyConfig(source_dir));
  ASSERT_TRUE(source.Run().finished);
  const std::string model_path = source_dir + "/model.pt";
  ExportCheckpoint(source_dir + "/checkpoint_final.pt", model_path);

  // Distance of a trainer's weights from the source's after one step of its schedule.
  auto distance_after_one_step = [&](const std::string& init_from, const std::string& name) {
    StackNetConfig config = TinyConfig(TempDir(name));
    config.train.seed += 1;  // another seeded initialisation than the source's
    config.train.init_from = init_from;
    EXPECT_EQ(ConfigToYaml(ParseConfig(ConfigToYaml(config))), ConfigToYaml(config));  // the key round-trips
    Trainer trainer(config, [](const TrainingPosition& p) { return p.global_step == 1; });
    EXPECT_TRUE(trainer.Run().interrupted);
    double sum = 0;
    const auto a = source.model()->named_parameters();
    const auto b = trainer.model()->named_parameters();
    for (size_t i = 0; i < a.size(); ++i) sum += (a[i].value() - b[i].value()).abs().sum().item<double>();
    return sum;
  };
  const double from_scratch = distance_after_one_step("", "init_none");
  const double initialised = distance_after_one_step(model_path, "init_model");
  EXPECT_LT(initialised, 0.05 * from_scratch) << initialised << " vs " << from_scratch;
}

TEST_F(SimulatedTraining, ResumeAfterAnInterruptionContinuesExactly) {
  at::set_num_threads(1);
  StackNetConfig config = ResumeConfig(TempDir("full"));
  Trainer full(config);
  ASSERT_TRUE(full.Run().finished);

  config.train.output_dir = TempDir("resumed");
  const TrainResult stop = RunUntilStep(config, 2);
  ASSERT_TRUE(stop.interrupted);
  EXPECT_EQ(stop.position.stage, 0);
  EXPECT_EQ(stop.position.batch, 2);
  Trainer resumed(config);
  const TrainResult done = resumed.Run(stop.last_checkpoint);
  ASSERT_TRUE(done.finished);
  EXPECT_EQ(done.position.global_step, 8);  // 2 x 3 + 2

  const auto a = full.model()->named_parameters();
  const auto b = resumed.model()->named_parameters();
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(torch::equal(a[i].value(), b[i].value())) << a[i].key() << " differs after resume";
  }
}

std::string ReadAll(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Inside a stage, the batch size, the seed and the stage's data decide which samples the remaining batch
// indices are: a resume with other values is refused, naming the key, and (like any refused resume, or a
// run whose data does not open) before config.yaml or the logs change, so config.yaml still describes the
// checkpoints beside it. At a stage boundary the next stage starts afresh and they may change.
TEST_F(SimulatedTraining, RefusedResumeLeavesTheOutputFolderAsItWas) {
  at::set_num_threads(1);
  const StackNetConfig config = ResumeConfig(TempDir("refused"));
  const TrainResult stop = RunUntilStep(config, 2);
  ASSERT_TRUE(stop.interrupted);
  ASSERT_EQ(stop.position.batch, 2);
  const std::string out = config.train.output_dir;
  const std::string config_yaml = ReadAll(out + "/config.yaml"), csv = ReadAll(out + "/losses.csv"),
                    epochs = ReadAll(out + "/epochs.jsonl");
  ASSERT_EQ(config_yaml, ConfigToYaml(config));
  ASSERT_NE(csv.find("\n0,simple_semi,0,1,2,"), std::string::npos) << csv;  // the steps before the stop

  auto refused = [&](const std::string& what, const std::function<void(StackNetConfig&)>& change,
                     const std::string& key, const std::string& checkpoint) {
    SCOPED_TRACE(what);
    StackNetConfig changed = config;
    change(changed);
    try {
      Trainer trainer(changed);
      trainer.Run(checkpoint);
      ADD_FAILURE() << "run accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
    EXPECT_EQ(ReadAll(out + "/config.yaml"), config_yaml);
    EXPECT_EQ(ReadAll(out + "/losses.csv"), csv);
    EXPECT_EQ(ReadAll(out + "/epochs.jsonl"), epochs);
  };
  const std::string last = stop.last_checkpoint;
  refused("batch size", [](StackNetConfig& c) { c.train.batch_size = 1; }, "train.batch_size", last);
  refused("seed", [](StackNetConfig& c) { c.train.seed += 1; }, "train.seed", last);
  refused("sequences", [&](StackNetConfig& c) { c.data.sequences.push_back(sequence_); }, "data.sequences", last);
  refused("frame step", [](StackNetConfig& c) { c.data.frame_step = 2; }, "data.frame_step", last);
  refused("network", [](StackNetConfig& c) { c.network.width_multiplier = 0.25; }, "network options", last);
  // Not a resume: a run whose data does not open leaves the earlier run's files too.
  refused("missing sequence", [](StackNetConfig& c) { c.data.sequences = {"/nonexistent/sequence"}; },
          "/nonexistent/sequence", "");

  // The unchanged config resumes; from the stage-0 checkpoint, stage 1 may use another batch size and seed.
  Trainer resumed(config);
  ASSERT_TRUE(resumed.Run(last).finished);
  StackNetConfig next_stage = config;
  next_stage.train.batch_size = 1;
  next_stage.train.seed += 1;
  Trainer boundary(next_stage);
  EXPECT_TRUE(boundary.Run(boundary.StageCheckpointPath(0)).finished);
}

// epochs.jsonl after resumes: an interruption on an epoch's last batch, and a resume from an older
// checkpoint, leave one record per epoch with the steps and mean loss of an uninterrupted run.
TEST_F(SimulatedTraining, EpochLogAfterResumesHasOneRecordPerEpoch) {
  at::set_num_threads(1);
  StackNetConfig config = ResumeConfig(TempDir("epochs_full"));
  Trainer full(config);
  ASSERT_TRUE(full.Run().finished);
  auto read_log = [](const std::string& dir) {
    std::vector<nlohmann::json> records;
    std::ifstream in(dir + "/epochs.jsonl");
    for (std::string line; std::getline(in, line);) records.push_back(nlohmann::json::parse(line));
    return records;
  };
  const std::vector<nlohmann::json> expected = read_log(config.train.output_dir);
  ASSERT_EQ(expected.size(), 3u);  // stage 0: 2 epochs, stage 1: 1
  auto expect_like_full_run = [&](const std::string& dir, const std::string& when) {
    const std::vector<nlohmann::json> records = read_log(dir);
    ASSERT_EQ(records.size(), expected.size()) << when;
    for (size_t i = 0; i < records.size(); ++i) {
      EXPECT_GT(records[i]["steps"].get<int>(), 0) << when << ": record " << i;
      for (const char* key : {"stage", "epoch", "steps", "global_step"}) {
        EXPECT_EQ(records[i][key].get<int64_t>(), expected[i][key].get<int64_t>()) << when << ": record " << i << " " << key;
      }
      // The steps before an interruption come back from losses.csv (6 significant digits).
      const double mean = expected[i]["mean_total"].get<double>();
      EXPECT_NEAR(records[i]["mean_total"].get<double>(), mean, 1e-4 * std::abs(mean)) << when << ": record " << i;
    }
  };

  config.train.output_dir = TempDir("epochs_resumed");
  // Step 3 is the last batch of stage 0's first epoch: the resumed run has no step left in it.
  const TrainResult stop = RunUntilStep(config, 3);
  ASSERT_TRUE(stop.interrupted);
  ASSERT_EQ(stop.position.epoch, 0);
  ASSERT_EQ(stop.position.batch, 3);
  Trainer resumed(config);
  ASSERT_TRUE(resumed.Run(stop.last_checkpoint).finished);
  expect_like_full_run(config.train.output_dir, "resumed on an epoch's last batch");
  // `seconds` times the steps of the run that finished the epoch: none of the resumed epoch's 3.
  const std::vector<nlohmann::json> timed = read_log(config.train.output_dir);
  ASSERT_EQ(timed.size(), 3u);
  EXPECT_EQ(timed[0]["timed_steps"].get<int>(), 0);
  EXPECT_EQ(timed[1]["timed_steps"].get<int>(), timed[1]["steps"].get<int>());

  // The finished run resumed from its stage-0 checkpoint redoes stage 1 and logs it once.
  Trainer again(config);
  ASSERT_TRUE(again.Run(again.StageCheckpointPath(0)).finished);
  expect_like_full_run(config.train.output_dir, "resumed from an older checkpoint");

  // Interrupted inside stage 0's second epoch, resumed with a config that has only one epoch there: that
  // epoch is skipped, and its step before the interruption does not land in stage 1's record.
  config.train.output_dir = TempDir("epochs_shortened");
  const TrainResult inside_stop = RunUntilStep(config, 4);
  ASSERT_TRUE(inside_stop.interrupted);
  ASSERT_EQ(inside_stop.position.epoch, 1);
  ASSERT_EQ(inside_stop.position.batch, 1);
  StackNetConfig shortened = config;
  shortened.stages[0].epochs = 1;
  Trainer shortened_run(shortened);
  ASSERT_TRUE(shortened_run.Run(inside_stop.last_checkpoint).finished);
  const std::vector<nlohmann::json> records = read_log(shortened.train.output_dir);
  ASSERT_FALSE(records.empty());
  EXPECT_EQ(records.back()["stage"].get<int>(), 1);
  EXPECT_EQ(records.back()["steps"].get<int>(), expected.back()["steps"].get<int>());
}

}  // namespace
}  // namespace dvso::stacknet
