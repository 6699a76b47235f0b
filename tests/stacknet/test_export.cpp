// TorchScript export: the traced module reproduces the C++ module (1e-5),
// also at an input size other than the traced one, and loads from disk.
#include <gtest/gtest.h>
#include <torch/script.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/sequence.h"
#include "stacknet/predictor.h"

#include "stacknet/checkpoint.h"
#include "stacknet/config.h"
#include "stacknet/dataset.h"
#include "stacknet/device.h"
#include "stacknet/export.h"
#include "stacknet_test_util.h"
#include "tests/dvso_cli_runner.h"
#include "tests/temp_dir.h"

namespace dvso::stacknet {
namespace {
namespace fs = std::filesystem;

double MaxDifference(const torch::Tensor& a, const torch::Tensor& b) { return (a - b).abs().max().item<double>(); }

// A tiny StackNet in eval mode whose residual path is non-trivial (its heads start at zero).
StackNet TinyStackNetWithResidual(uint64_t seed) {
  torch::manual_seed(seed);
  StackNet net(testing::TinyNetwork());
  torch::NoGradGuard no_grad;
  for (auto& p : net->residual_net()->parameters()) p.add_(torch::randn_like(p) * 0.005);
  net->eval();
  return net;
}

TEST(Export, TracedModuleMatchesTheCppModuleAtTwoSizes) {
  StackNet net = TinyStackNetWithResidual(9);
  const std::string path = dvso::testing::ScratchPath("export.pt");
  for (const bool use_residual : {false, true}) {
    torch::jit::Module traced = TraceStackNet(net, use_residual, 32, 64);
    traced.save(path);
    torch::jit::Module loaded = torch::jit::load(path);
    EXPECT_EQ(loaded.attr("input_width").toInt(), 64);
    // Exactly the weights of the exported network travel with it.
    const size_t expected_parameters =
        use_residual ? net->parameters().size() : net->simple_net()->parameters().size();
    EXPECT_EQ(loaded.parameters().size(), expected_parameters);
    for (const auto& size : {std::pair<int, int>{32, 64}, std::pair<int, int>{64, 128}}) {
      const torch::Tensor image = torch::rand({1, 3, size.first, size.second});
      torch::NoGradGuard no_grad;
      const auto [left, right] = InferPixels(net, use_residual, image);
      const auto out = loaded.forward({image}).toTuple();
      const torch::Tensor traced_left = out->elements()[0].toTensor();
      const torch::Tensor traced_right = out->elements()[1].toTensor();
      ASSERT_EQ(traced_left.sizes(), left.sizes());
      EXPECT_LT(MaxDifference(traced_left, left), 1e-5) << "residual " << use_residual << " size " << size.second;
      EXPECT_LT(MaxDifference(traced_right, right), 1e-5);
      // Pixels of the input: bounded by max_disparity * width.
      EXPECT_GT(left.max().item<double>(), 0.0);
      if (!use_residual) {
        EXPECT_LT(left.max().item<double>(), 0.3 * size.second);
      }
    }
  }
  fs::remove(path);
}

TEST(Export, InferenceLayoutGivesTheSameDisparities) {
  StackNet net = TinyStackNetWithResidual(11);
  torch::jit::Module module = TraceStackNet(net, /*use_residual=*/true, 32, 64);
  const torch::Tensor image = torch::rand({1, 3, 64, 128});
  torch::NoGradGuard no_grad;
  const auto reference = module.forward({image}).toTuple();
  const torch::Device cpu(torch::kCPU);
  UseInferenceLayout(module, cpu);
  size_t channels_last = 0;
  for (const torch::Tensor& p : module.parameters()) {
    if (p.dim() == 4) channels_last += p.is_contiguous(at::MemoryFormat::ChannelsLast) && !p.is_contiguous();
  }
  EXPECT_GT(channels_last, 0u);  // the layout did change (1x1 kernels are both)
  const torch::Tensor input = ToConvolutionLayout(image, cpu);
  EXPECT_TRUE(input.is_contiguous(at::MemoryFormat::ChannelsLast));
  // An NHWC buffer viewed as NCHW (how the predictor wraps an image) is used as it is.
  const torch::Tensor nhwc_view = input.permute({0, 2, 3, 1}).contiguous().permute({0, 3, 1, 2});
  EXPECT_EQ(ToConvolutionLayout(nhwc_view, cpu).data_ptr(), nhwc_view.data_ptr());
  const auto converted = module.forward({input}).toTuple();
  for (int i = 0; i < 2; ++i) {
    EXPECT_LT(MaxDifference(reference->elements()[i].toTensor(), converted->elements()[i].toTensor()), 1e-4);
  }
}

// The config of a tiny network trained on a sequence that is not on this machine, and its checkpoint record.
StackNetConfig TinyTrainedConfig() {
  StackNetConfig config;
  config.network = testing::TinyNetwork();
  config.data.sequences = {"unused"};
  config.stages.resize(1);
  return config;
}

CheckpointInfo TinyCheckpointInfo(const StackNetConfig& config) {
  CheckpointInfo info;
  info.config_yaml = ConfigToYaml(config);
  info.trained_model = "simple";
  info.config_name = "stacknet_tiny";
  return info;
}

TEST(Export, CheckpointExportUsesTheTrainedNetwork) {
  torch::manual_seed(4);
  const StackNetConfig config = TinyTrainedConfig();
  StackNet net(config.network);
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_ckpt"));
  fs::create_directories(dir);
  CheckpointInfo info = TinyCheckpointInfo(config);
  SaveCheckpoint((dir / "c.pt").string(), net, nullptr, info);
  EXPECT_EQ(ReadCheckpointInfo((dir / "c.pt").string()).config_name, "stacknet_tiny");
  // The config's sequences are gone: the training camera must be given.
  EXPECT_THROW(ExportCheckpoint((dir / "c.pt").string(), (dir / "m.pt").string()), Error);
  ExportOptions options;
  options.training_baseline = 0.54;
  options.training_fx_over_width = 0.58;
  const std::string description = ExportCheckpoint((dir / "c.pt").string(), (dir / "m.pt").string(), options);
  EXPECT_NE(description.find("SimpleNet"), std::string::npos) << description;
  torch::jit::Module loaded = torch::jit::load((dir / "m.pt").string());
  EXPECT_FALSE(loaded.attr("uses_residual").toBool());
  const torch::Tensor image = torch::rand({1, 3, 32, 64});
  net->eval();
  torch::NoGradGuard no_grad;
  const auto [left, right] = InferPixels(net, false, image);
  EXPECT_LT(MaxDifference(loaded.forward({image}).toTuple()->elements()[0].toTensor(), left), 1e-5);
  // The metadata travels in the file (also readable from Python's torch.jit.load(_extra_files=...)).
  const ModelMetadata metadata = ReadModelMetadata((dir / "m.pt").string());
  EXPECT_DOUBLE_EQ(metadata.baseline, 0.54);
  EXPECT_DOUBLE_EQ(metadata.fx_over_width, 0.58);
  EXPECT_EQ(metadata.input_width, config.network.input_width);
  EXPECT_EQ(metadata.model_kind, "simple");
  EXPECT_EQ(metadata.config_name, "stacknet_tiny");  // the config's name, not where it was trained
  const TorchDisparityPredictor predictor((dir / "m.pt").string());
  EXPECT_DOUBLE_EQ(predictor.metadata().baseline, 0.54);
  // Stamping metadata onto a file keeps the network.
  ModelMetadata stamped = metadata;
  stamped.baseline = 0.3;
  WriteModelWithMetadata((dir / "m.pt").string(), (dir / "s.pt").string(), stamped);
  EXPECT_DOUBLE_EQ(ReadModelMetadata((dir / "s.pt").string()).baseline, 0.3);
  fs::remove_all(dir);
}

// What a lent GPU machine sends back (scripts/gpu/train_on_device.sh): the checkpoint without its Adam state, which
// must export to the same network as the full checkpoint.
TEST(Export, WeightsOnlyCheckpointExportsTheSameNetwork) {
  torch::manual_seed(5);
  const StackNetConfig config = TinyTrainedConfig();
  StackNet net(config.network);
  torch::optim::Adam optimizer(net->parameters(), torch::optim::AdamOptions(1e-3));
  // One step, so the optimiser has state (exp_avg, exp_avg_sq per parameter: twice the weights).
  const torch::Tensor image = torch::rand({1, 3, 32, 64});
  net->forward(image).simple.left[0].mean().backward();
  optimizer.step();
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_weights_only"));
  fs::create_directories(dir);
  CheckpointInfo info = TinyCheckpointInfo(config);
  info.position.global_step = 17;
  SaveCheckpoint((dir / "full.pt").string(), net, &optimizer, info);
  WriteWeightsOnlyCheckpoint((dir / "full.pt").string(), (dir / "weights.pt").string());
  // Adam keeps two tensors per parameter that had a gradient (here SimpleNet's: ResidualNet was not in the step).
  EXPECT_LT(fs::file_size(dir / "weights.pt") * 3, fs::file_size(dir / "full.pt") * 2);
  const CheckpointInfo copied = ReadCheckpointInfo((dir / "weights.pt").string());
  EXPECT_EQ(copied.config_name, "stacknet_tiny");
  EXPECT_EQ(copied.position.global_step, 17);
  EXPECT_EQ(copied.config_yaml, info.config_yaml);
  ExportOptions options;
  options.training_baseline = 0.54;
  options.training_fx_over_width = 0.58;
  ExportCheckpoint((dir / "full.pt").string(), (dir / "full_model.pt").string(), options);
  ExportCheckpoint((dir / "weights.pt").string(), (dir / "weights_model.pt").string(), options);
  torch::jit::Module from_full = torch::jit::load((dir / "full_model.pt").string());
  torch::jit::Module from_weights = torch::jit::load((dir / "weights_model.pt").string());
  torch::NoGradGuard no_grad;
  EXPECT_EQ(MaxDifference(from_full.forward({image}).toTuple()->elements()[0].toTensor(),
                          from_weights.forward({image}).toTuple()->elements()[0].toTensor()),
            0.0);
  // The command refuses what a copy cannot record.
  const auto refused = dvso::testing::RunDvso("export --checkpoint " + (dir / "full.pt").string() +
                                              " --weights-only --model stack --out " + (dir / "x.pt").string());
  EXPECT_NE(refused.exit_code, 0);
  EXPECT_NE(refused.out.find("--model describes an export"), std::string::npos) << refused.out;
  const auto copied_cli = dvso::testing::RunDvso("export --checkpoint " + (dir / "full.pt").string() +
                                                 " --weights-only --out " + (dir / "cli.pt").string());
  ASSERT_EQ(copied_cli.exit_code, 0) << copied_cli.out;
  StackNet from_cli = LoadModelFromCheckpoint((dir / "cli.pt").string());
  net->eval();
  EXPECT_EQ(MaxDifference(from_cli->forward(image).refined.left[0], net->forward(image).refined.left[0]), 0.0);
  EXPECT_LT(fs::file_size(dir / "cli.pt") * 3, fs::file_size(dir / "full.pt") * 2);
  fs::remove_all(dir);
}

// Training reads a KITTI raw drive through its colour pair 02/03, so the exported model's training
// camera is that pair's, not the grey pair's, also where the two baselines differ.
TEST(Export, TrainingCameraOfARawDriveIsItsColourPair) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_raw_camera"));
  const std::string sim = std::string(DVSO_BINARY) + " simulate --quiet --out " + (dir / "seq").string() +
                          " --count 4 --width 128 --height 64 --color --raw-layout sync > /dev/null 2>&1";
  ASSERT_EQ(std::system(sim.c_str()), 0) << sim;
  const fs::path date = dir / "seq" / "kitti_raw" / "2011_09_26";
  const std::string drive = (date / "2011_09_26_drive_0001_sync").string();
  // The right colour camera 10 cm further right than the grey one: the two pairs' baselines differ.
  std::string lines, line;
  int moved = 0;
  for (std::ifstream in(date / "calib_cam_to_cam.txt"); std::getline(in, line);) {
    if (line.rfind("P_rect_03:", 0) == 0) {
      std::istringstream values(line.substr(10));
      std::vector<double> p(12);
      for (double& v : p) values >> v;
      p[3] -= p[0] * 0.1;
      line = "P_rect_03:";
      for (double v : p) line += " " + std::to_string(v);
      ++moved;
    }
    lines += line + "\n";
  }
  ASSERT_EQ(moved, 1);
  std::ofstream(date / "calib_cam_to_cam.txt") << lines;
  const StereoCamera grey = OpenSequence(drive)->camera();
  const StereoCamera colour = OpenSequence(drive, "", CameraPair::kColour)->camera();
  ASSERT_NEAR(colour.baseline - grey.baseline, 0.1, 1e-4);
  EXPECT_DOUBLE_EQ(OpenTrainingSequence(drive)->camera().baseline, colour.baseline);

  torch::manual_seed(6);
  StackNetConfig config;
  config.network = testing::TinyNetwork();
  config.data.sequences = {drive};
  config.stages.resize(1);
  StackNet net(config.network);
  CheckpointInfo info;
  info.config_yaml = ConfigToYaml(config);
  SaveCheckpoint((dir / "c.pt").string(), net, nullptr, info);
  ExportCheckpoint((dir / "c.pt").string(), (dir / "m.pt").string());
  const ModelMetadata metadata = ReadModelMetadata((dir / "m.pt").string());
  EXPECT_DOUBLE_EQ(metadata.baseline, colour.baseline);
  EXPECT_DOUBLE_EQ(metadata.fx_over_width, colour.left.fx / colour.left.width);

  // A split file's drives (configs/stacknet_paper.yaml trains on splits only), resolved like the dataset
  // resolves them (under split_root); a split file that is not on this machine is skipped.
  std::ofstream(dir / "split.txt") << "2011_09_26/2011_09_26_drive_0001_sync 0000000002 l\n";
  auto split_config = [&](const std::string& split_file) {
    return "network: {encoder_depth: 18}\ndatasets: {K_o: {split_file: " + split_file + ", split_root: " +
           (dir / "seq" / "kitti_raw").string() + "}}\nstages: [{data: K_o}]\n";
  };
  double baseline = 0, fx_over_width = 0;
  ASSERT_TRUE(TrainingCameraFromConfig(split_config((dir / "split.txt").string()), &baseline, &fx_over_width));
  EXPECT_DOUBLE_EQ(baseline, colour.baseline);
  EXPECT_DOUBLE_EQ(fx_over_width, colour.left.fx / colour.left.width);
  EXPECT_FALSE(TrainingCameraFromConfig(split_config((dir / "gone.txt").string()), &baseline, &fx_over_width));
  fs::remove_all(dir);
}

// The training camera is that of the data the stages trained on (not data: when every stage names a
// dataset); sequences no longer on this machine are skipped, one that is there but unreadable is an error
// (not a reason to take the next sequence's camera, maybe another one).
TEST(Export, TrainingCameraComesFromTheDataTheStagesUsed) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_stage_camera"));
  for (const auto& [name, baseline] :
       std::vector<std::pair<std::string, std::string>>{{"narrow", "0.3"}, {"wide", "0.6"}}) {
    const std::string sim = std::string(DVSO_BINARY) + " simulate --quiet --out " + (dir / name).string() +
                            " --count 2 --width 128 --height 64 --baseline " + baseline + " > /dev/null 2>&1";
    ASSERT_EQ(std::system(sim.c_str()), 0) << sim;
  }
  const std::string narrow = (dir / "narrow").string(), wide = (dir / "wide").string();
  auto camera = [](const std::string& yaml) {
    double baseline = 0, fx_over_width = 0;
    EXPECT_TRUE(TrainingCameraFromConfig(yaml, &baseline, &fx_over_width)) << yaml;
    return baseline;
  };
  const std::string data = "data: {sequences: [" + narrow + "]}\n";
  // Every stage on a named dataset: data: was never read.
  EXPECT_NEAR(camera(data + "datasets: {K: {sequences: [" + wide + "]}}\nstages: [{data: K}]\n"), 0.6, 1e-3);
  // In stage order.
  EXPECT_NEAR(camera(data + "datasets: {K: {sequences: [" + wide + "]}}\nstages: [{}, {data: K}]\n"), 0.3, 1e-3);
  EXPECT_NEAR(camera(data + "datasets: {K: {sequences: [" + wide + "]}}\nstages: [{data: K}, {}]\n"), 0.6, 1e-3);
  // Gone: skipped.
  EXPECT_NEAR(camera("data: {sequences: [" + (dir / "gone").string() + ", " + wide + "]}\nstages: [{}]\n"), 0.6,
              1e-3);
  // There but unreadable: an error naming its calibration.
  fs::copy(narrow, dir / "corrupt", fs::copy_options::recursive);
  std::ofstream(dir / "corrupt" / "calib.txt") << "P0: 1 2 3\n";
  double baseline = 0, fx_over_width = 0;
  try {
    TrainingCameraFromConfig("data: {sequences: [" + (dir / "corrupt").string() + ", " + wide + "]}\nstages: [{}]\n",
                             &baseline, &fx_over_width);
    ADD_FAILURE() << "an unreadable sequence was skipped; baseline " << baseline;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("calib.txt"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

TEST(Export, ExportedWeightsInitialiseANewNetworkForFineTuning) {
  torch::manual_seed(21);
  StackNet source(testing::TinyNetwork());
  {
    torch::NoGradGuard no_grad;
    for (auto& p : source->residual_net()->parameters()) p.add_(torch::randn_like(p) * 0.005);
  }
  source->eval();
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_init"));
  fs::create_directories(dir);
  const std::string stack_path = (dir / "stack.pt").string();
  const std::string simple_path = (dir / "simple.pt").string();
  TraceStackNet(source, /*use_residual=*/true, 32, 64).save(stack_path);
  TraceStackNet(source, /*use_residual=*/false, 32, 64).save(simple_path);
  const torch::Tensor image = torch::rand({1, 3, 32, 64});
  torch::NoGradGuard no_grad;
  const auto [source_left, source_right] = InferPixels(source, true, image);

  // Another seed gives other weights; loading the StackNet export makes it the same network.
  torch::manual_seed(22);
  StackNet target(testing::TinyNetwork());
  target->eval();
  EXPECT_GT(MaxDifference(InferPixels(target, true, image).first, source_left), 1e-3);
  EXPECT_EQ(LoadWeightsFromExport(stack_path, target), static_cast<int>(source->parameters().size()));
  EXPECT_LT(MaxDifference(InferPixels(target, true, image).first, source_left), 1e-6);
  EXPECT_LT(MaxDifference(InferPixels(target, true, image).second, source_right), 1e-6);

  // A SimpleNet export sets SimpleNet and leaves the ResidualNet as it was.
  torch::manual_seed(23);
  StackNet partial(testing::TinyNetwork());
  partial->eval();
  const torch::Tensor residual_before = partial->residual_net()->parameters().front().clone();
  EXPECT_EQ(LoadWeightsFromExport(simple_path, partial), static_cast<int>(source->simple_net()->parameters().size()));
  EXPECT_LT(MaxDifference(InferPixels(partial, false, image).first, InferPixels(source, false, image).first), 1e-6);
  EXPECT_EQ(MaxDifference(partial->residual_net()->parameters().front(), residual_before), 0.0);

  // Another architecture (twice the width) is an error naming the file, not a partial load.
  NetworkOptions wider = testing::TinyNetwork();
  wider.width_multiplier = 0.25;
  StackNet other(wider);
  try {
    LoadWeightsFromExport(stack_path, other);
    FAIL() << "weights of another width were loaded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("stack.pt"), std::string::npos) << e.what();
  }
  // A file that is not TorchScript.
  std::ofstream((dir / "text.pt").string()) << "not a model";
  EXPECT_THROW(LoadWeightsFromExport((dir / "text.pt").string(), target), Error);
  fs::remove_all(dir);
}

// Options that are no parameters change what the same weights compute; the export records them and
// --init-from refuses a network built with other values (a raw-input ResidualNet into a standardising
// one once loaded "successfully").
TEST(Export, InitFromRejectsAnExportWhoseNonParameterOptionsDiffer) {
  NetworkOptions raw = testing::TinyNetwork();
  raw.standardize_residual_inputs = false;
  torch::manual_seed(31);
  StackNet source(raw);
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_options"));
  fs::create_directories(dir);
  const std::string stack_path = (dir / "raw_stack.pt").string();
  TraceStackNet(source, /*use_residual=*/true, 32, 64).save(stack_path);
  const torch::jit::Module loaded = torch::jit::load(stack_path);
  EXPECT_DOUBLE_EQ(loaded.attr("max_disparity").toDouble(), raw.max_disparity);
  EXPECT_DOUBLE_EQ(loaded.attr("residual_leaky_slope").toDouble(), raw.residual_leaky_slope);
  EXPECT_FALSE(loaded.attr("standardize_residual_inputs").toBool());

  auto load_error = [&](const NetworkOptions& options) {
    StackNet target(options);
    try {
      LoadWeightsFromExport(stack_path, target);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  NetworkOptions standardized = raw;
  standardized.standardize_residual_inputs = true;
  const std::string standardize_error = load_error(standardized);
  EXPECT_NE(standardize_error.find("raw_stack.pt"), std::string::npos) << standardize_error;
  EXPECT_NE(standardize_error.find("standardize_residual_inputs false"), std::string::npos) << standardize_error;
  EXPECT_EQ(standardize_error.find('\n'), std::string::npos) << standardize_error;

  NetworkOptions wider_range = raw;
  wider_range.max_disparity = 0.5;
  const std::string range_error = load_error(wider_range);
  EXPECT_NE(range_error.find("raw_stack.pt"), std::string::npos) << range_error;
  EXPECT_NE(range_error.find("max_disparity 0.3"), std::string::npos) << range_error;
  EXPECT_NE(range_error.find("0.5"), std::string::npos) << range_error;

  NetworkOptions other_slope = raw;
  other_slope.residual_leaky_slope = 0.2;
  EXPECT_NE(load_error(other_slope).find("residual_leaky_slope"), std::string::npos) << load_error(other_slope);

  // The same options load, and so does a SimpleNet export into a standardising network (its
  // ResidualNet starts fresh, so the export's ResidualNet options do not apply).
  StackNet same(raw);
  EXPECT_EQ(LoadWeightsFromExport(stack_path, same), static_cast<int>(source->parameters().size()));
  const std::string simple_path = (dir / "raw_simple.pt").string();
  TraceStackNet(source, /*use_residual=*/false, 32, 64).save(simple_path);
  StackNet fresh_residual(standardized);
  EXPECT_EQ(LoadWeightsFromExport(simple_path, fresh_residual),
            static_cast<int>(source->simple_net()->parameters().size()));
  fs::remove_all(dir);
}

// Exports written before the options were recorded (the shipped model of sessions 13-32, for one) carry none of
// them and load as before, whatever the target's options (nothing to compare with). Such a file, as
// TraceStackNet wrote it then: the weights (dots as underscores), the input size and uses_residual, no options.
TEST(Export, ExportsWithoutRecordedOptionsLoadAsBefore) {
  const NetworkOptions options = testing::TinyNetwork();
  torch::manual_seed(37);
  StackNet source(options);
  torch::jit::Module old_export("DvsoStackNet");
  for (const auto& item : source->named_parameters()) {
    std::string name = item.key();
    std::replace(name.begin(), name.end(), '.', '_');
    old_export.register_parameter(name, item.value(), /*is_buffer=*/false);
  }
  old_export.register_attribute("input_height", c10::IntType::get(), c10::IValue(int64_t{32}));
  old_export.register_attribute("input_width", c10::IntType::get(), c10::IValue(int64_t{64}));
  old_export.register_attribute("uses_residual", c10::BoolType::get(), c10::IValue(true));
  const std::string path = dvso::testing::ScratchPath("export_without_options.pt");
  old_export.save(path);
  ASSERT_FALSE(torch::jit::load(path).hasattr("standardize_residual_inputs"));

  NetworkOptions other = options;
  other.standardize_residual_inputs = !other.standardize_residual_inputs;
  other.residual_leaky_slope = options.residual_leaky_slope + 0.1;
  StackNet target(other);
  EXPECT_EQ(LoadWeightsFromExport(path, target), static_cast<int>(target->parameters().size()));
  torch::NoGradGuard no_grad;
  EXPECT_TRUE(torch::equal(target->parameters().front(), source->parameters().front()));
  fs::remove(path);
}

TEST(Export, ShippedModelNamesTheConfigItWasTrainedWith) {
  // Issue 10: the metadata carries the training config's name; for the shipped model that config
  // is in configs/ and describes the network in the file.
  const std::string root = std::string(DVSO_TEST_DATA_DIR) + "/..";
  const ModelMetadata metadata = ReadModelMetadata(root + "/models/stacknet_cpu_main.pt");
  ASSERT_FALSE(metadata.config_name.empty());
  const std::string config_path = root + "/configs/" + metadata.config_name + ".yaml";
  ASSERT_TRUE(fs::exists(config_path)) << config_path;
  const StackNetConfig config = LoadConfig(config_path, /*check=*/false);
  EXPECT_EQ(config.network.input_width, metadata.input_width);
  EXPECT_EQ(config.network.input_height, metadata.input_height);
  EXPECT_EQ(metadata.model_kind, "stack");
}

TEST(Export, PredictorRejectsFilesThatAreNotDvsoModelsWithOneLine) {
  const fs::path dir = fs::path(dvso::testing::ScratchPath("export_bad"));
  fs::create_directories(dir);
  {
    std::ofstream((dir / "text.pt").string()) << "not a model";
  }
  try {
    TorchDisparityPredictor p((dir / "text.pt").string());
    FAIL() << "a text file loaded as a model";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("text.pt"), std::string::npos) << e.what();
  }
  // A TorchScript module whose output is one map instead of (left, right).
  torch::jit::Module one("OneMap");
  one.register_attribute("input_width", c10::IntType::get(), c10::IValue(int64_t{64}));
  one.register_attribute("input_height", c10::IntType::get(), c10::IValue(int64_t{32}));
  one.define("def forward(self, x):\n  return x[:, 0:1]\n");
  one.save((dir / "one.pt").string());
  TorchDisparityPredictor predictor((dir / "one.pt").string());
  try {
    predictor.PredictImage(cv::Mat(20, 40, CV_8UC1, cv::Scalar(100)));
    FAIL() << "a one-map output was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not 2 float maps"), std::string::npos) << e.what();
  }
  fs::remove_all(dir);
}

// `dvso export --random-init` of the tiny config (the CLI tests below), writing SimpleNet to `out`.
std::string ExportTinyRandomInit(const std::string& extra_args, const std::string& out) {
  return "export --config " + std::string(DVSO_TEST_DATA_DIR) + "/../configs/stacknet_tiny.yaml --random-init " +
         "--model simple " + extra_args + " --out " + out;
}

// The training camera (and config name) given to `export --random-init` reach the file's metadata, so that
// `odometry --model` accepts it; half a camera is refused rather than written.
TEST(ExportCli, RandomInitRecordsTheGivenTrainingCamera) {
  const fs::path dir = fs::path(dvso::testing::ScratchDir("export_cli_random"));
  const std::string model = (dir / "m.pt").string();
  const dvso::testing::CliRun run = dvso::testing::RunDvso(ExportTinyRandomInit(
      "--training-baseline 0.54 --training-fx-over-width 0.58 --config-name tiny_architecture", model));
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const ModelMetadata metadata = ReadModelMetadata(model);
  EXPECT_DOUBLE_EQ(metadata.baseline, 0.54);
  EXPECT_DOUBLE_EQ(metadata.fx_over_width, 0.58);
  EXPECT_EQ(metadata.config_name, "tiny_architecture");
  EXPECT_EQ(metadata.model_kind, "simple");
  const std::string half = (dir / "half.pt").string();
  const dvso::testing::CliRun refused = dvso::testing::RunDvso(ExportTinyRandomInit("--training-baseline 0.54", half));
  EXPECT_EQ(refused.exit_code, 1) << refused.out;
  EXPECT_EQ(std::count(refused.out.begin(), refused.out.end(), '\n'), 1) << "not one line: " << refused.out;
  EXPECT_FALSE(fs::exists(half));
}

// A metadata option that a mode of `dvso export` cannot record is a one-line usage error, never dropped.
TEST(ExportCli, MetadataOptionsAModeWouldDropAreErrors) {
  const fs::path dir = fs::path(dvso::testing::ScratchDir("export_cli_dropped"));
  const std::string base = (dir / "base.pt").string(), out = (dir / "out.pt").string();
  ASSERT_EQ(dvso::testing::RunDvso(
                ExportTinyRandomInit("--training-baseline 0.54 --training-fx-over-width 0.58", base)).exit_code,
            0);
  const std::string stamp = "export --stamp " + base + " --out " + out + " ";
  auto expect_usage_error = [&](const std::string& args, const std::string& named_option) {
    const dvso::testing::CliRun run = dvso::testing::RunDvso(args);
    EXPECT_EQ(run.exit_code, 1) << args << "\n" << run.out;
    EXPECT_NE(run.out.find(named_option), std::string::npos) << args << "\n" << run.out;
    EXPECT_EQ(std::count(run.out.begin(), run.out.end(), '\n'), 1) << "not one line: " << run.out;
    EXPECT_FALSE(fs::exists(out)) << args;
  };
  expect_usage_error(stamp + "--tuned-on 00", "--tuned-on");
  expect_usage_error(stamp + "--tuned-on 00 --tuned-baseline 0", "--tuned-on");
  expect_usage_error(stamp + "--model stack", "--model");
  expect_usage_error(ExportTinyRandomInit("--tuned-baseline 0.6", out), "--tuned-baseline");
  // Given together, both are stamped (and the camera is kept).
  const dvso::testing::CliRun run = dvso::testing::RunDvso(stamp + "--tuned-baseline 0.6 --tuned-on 00");
  ASSERT_EQ(run.exit_code, 0) << run.out;
  const ModelMetadata metadata = ReadModelMetadata(out);
  EXPECT_DOUBLE_EQ(metadata.tuned_baseline, 0.6);
  EXPECT_EQ(metadata.tuned_on, "00");
  EXPECT_DOUBLE_EQ(metadata.baseline, 0.54);
}

}  // namespace
}  // namespace dvso::stacknet
