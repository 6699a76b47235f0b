#include "pipelines/prediction_source.h"

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "core/error.h"
#include "core/fs_util.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void PredictionSourceArgs::Check() const {
  Require(disparity_left.empty() == disparity_right.empty(), "give both --disparity-left and --disparity-right");
  Require(disparity_left.empty() || model.empty(), "give either --model or --disparity-left/--disparity-right");
  Require(virtual_baseline >= 0, "--virtual-baseline must be > 0");
  if (!schedule.empty()) vo::ParsePredictionTiming(schedule);
  Require(threads >= 0, "--inference-threads must be >= 0");
}

void AddPredictionOptions(CLI::App* cmd, PredictionSourceArgs* args, const std::string& default_schedule) {
  cmd->add_option("--model", args->model,
                  std::string("dvso: TorchScript model from `dvso export`, run online (default: ") + kShippedModel + ")");
  cmd->add_option("--disparity-left", args->disparity_left,
                  "dvso: precomputed D^L: folder of KITTI uint16 PNGs named like the images, or a .npy stack "
                  "(N,H,W) normalised by width");
  cmd->add_option("--disparity-right", args->disparity_right, "dvso: precomputed D^R (same format)");
  cmd->add_option("--virtual-baseline", args->virtual_baseline,
                  "dvso: b_v in metres (default: the model's training baseline, or its tuned one, for every camera; for "
                  "files that of the model `dvso predict` recorded in their prediction_info.json, else the sequence's "
                  "baseline)")
      ->check(Positive());
  cmd->add_option("--prediction-schedule", args->schedule,
                  "dvso: keyframe-async (a keyframe's prediction runs on a worker while the next frames are tracked) | "
                  "keyframe-blocking (tracking waits for it: deterministic) | speculative (every frame predicted while "
                  "it is tracked); default: the config's dvso.prediction_timing, else " + default_schedule)
      ->check(CLI::IsMember({"keyframe-async", "keyframe-blocking", "speculative"}));
  cmd->add_option("--inference-threads", args->threads,
                  "dvso with a model: LibTorch threads (default 1: fastest beside the odometry on 2 cores; 0 = cores)");
}

void ApplyPredictionSource(const PredictionSourceArgs& args, PredictionSource* source,
                           vo::OdometryOptions* options) {
  // b_v from the model / files unless the config sets one and no flag overrides it.
  if (!(options->dvso.virtual_baseline > 0) || args.virtual_baseline > 0) {
    options->dvso.virtual_baseline = source->virtual_baseline;
  } else {
    // The run header must name the b_v the run uses, not the one the source proposed.
    std::ostringstream note;
    note << "; the config's dvso.virtual_baseline " << options->dvso.virtual_baseline << " m is used instead";
    source->description += note.str();
  }
  if (!args.schedule.empty()) options->dvso.prediction_timing = args.schedule;
}

std::string ShippedModelPath() {
  const std::string path = JoinPath(DVSO_SOURCE_DIR, kShippedModel);
  return std::filesystem::is_regular_file(path) ? path : "";
}

namespace {

// predict's record of the maps in `maps_dir` (one folder up). A trailing slash, as tab completion writes it,
// must not move the record's folder.
std::string PredictionRecordOf(const std::string& maps_dir) {
  return (NormalizedFolderPath(maps_dir).parent_path() / kPredictionInfoFile).string();
}

// Sets b_v (tuned and untuned) and the metadata from a model's training camera.
void TakeBaselinesOfModel(const ModelMetadata& metadata, PredictionSource* out) {
  out->untuned_virtual_baseline = VirtualBaselineOfModel(metadata, /*tuned=*/false);
  out->virtual_baseline = VirtualBaselineOfModel(metadata, /*tuned=*/true);
  out->tuned = metadata.tuned_baseline > 0;
  out->metadata = metadata;
}

}  // namespace

std::optional<ModelMetadata> RecordedModelMetadata(const std::string& maps_dir) {
  const std::string record = PredictionRecordOf(maps_dir);
  if (!std::filesystem::is_regular_file(record)) return std::nullopt;
  nlohmann::json j;
  try {
    std::ifstream in(record);
    in >> j;
  } catch (const std::exception& e) {
    throw Error(record, std::string("cannot parse: ") + e.what());
  }
  if (!j.is_object() || !j.contains("model_metadata")) return std::nullopt;
  RequireFile(j["model_metadata"].is_object(), record, "\"model_metadata\" must be an object");
  return ModelMetadata::FromJson(j["model_metadata"].dump(), record);
}

void RequireMapsOfCameraPair(const std::string& maps_dir, CameraPair pair) {
  if (maps_dir.empty()) return;
  const std::string record = PredictionRecordOf(maps_dir);
  const std::optional<CameraPair> recorded = RecordedCameraPair(record);
  if (!recorded || *recorded == pair) return;
  const std::string made = CameraPairName(*recorded), want = CameraPairName(pair);
  throw Error(record, "the maps were predicted on the " + made + " pair, this run reads the " + want +
                          " pair: pass --cameras " + made + " (or predict with --cameras " + want + ")");
}

PredictionSource OpenPredictionSource(const PredictionSourceArgs& args, const SequenceReader& sequence) {
  args.Check();
  PredictionSource out;
  std::ostringstream description;
  if (!args.disparity_left.empty()) {
    std::vector<std::string> names;
    names.reserve(sequence.size());
    for (int i = 0; i < sequence.size(); ++i) names.push_back(sequence.FrameName(i));
    RequireMapsOfCameraPair(args.disparity_left, sequence.camera_pair());
    RequireMapsOfCameraPair(args.disparity_right, sequence.camera_pair());
    out.source = std::make_unique<FileDisparitySource>(args.disparity_left, args.disparity_right, std::move(names));
    description << "disparities from files " << args.disparity_left << " / " << args.disparity_right;
    // Maps `dvso predict` wrote are the network's: b_v as if the model ran online (same scale either way).
    const std::optional<ModelMetadata> left_model = RecordedModelMetadata(args.disparity_left),
                                       right_model = RecordedModelMetadata(args.disparity_right);
    if (left_model && right_model)
      Require(left_model->ToJson() == right_model->ToJson(),
              "--disparity-left and --disparity-right were predicted by different models: " +
                  PredictionRecordOf(args.disparity_left) + " and " + PredictionRecordOf(args.disparity_right) +
                  " differ");
    const std::optional<ModelMetadata>& maker = left_model ? left_model : right_model;
    const std::string maker_record = PredictionRecordOf(left_model ? args.disparity_left : args.disparity_right);
    if (args.virtual_baseline > 0) {
      out.virtual_baseline = out.untuned_virtual_baseline = args.virtual_baseline;
    } else if (maker) {
      // As --model with that model: one without a training camera cannot say what its disparities mean.
      RequireFile(maker->has_camera(), maker_record,
                  "the model that predicted the maps carries no training camera: pass --virtual-baseline");
      TakeBaselinesOfModel(*maker, &out);
      description << " (predicted by a model trained with baseline " << maker->baseline << " m, as " << maker_record
                  << " records)";
    } else {
      // Maps from elsewhere (or predicted before session 40) are taken to be in this camera's stereo geometry.
      out.virtual_baseline = out.untuned_virtual_baseline = sequence.camera().baseline;
      Require(out.virtual_baseline > 0, sequence.root() +
                                            ": the sequence has no stereo baseline to interpret the disparity files: "
                                            "pass --virtual-baseline");
      description << " (no predicting model recorded with them: the sequence's stereo baseline)";
    }
  } else {
    std::string model = args.model;
    if (model.empty()) {
      model = ShippedModelPath();
      Require(!model.empty(), std::string("the shipped model ") + kShippedModel + " is missing: pass --model");
    }
    ModelMetadata metadata;
    std::unique_ptr<DisparitySource> network = OpenModelDisparitySource(model, args.threads, &metadata);
    if (args.virtual_baseline > 0) {
      out.virtual_baseline = out.untuned_virtual_baseline = args.virtual_baseline;
    } else {
      RequireFile(metadata.has_camera(), model,
                  "the model carries no training camera (re-export it with `dvso export`, or pass --virtual-baseline)");
      TakeBaselinesOfModel(metadata, &out);
    }
    out.metadata = metadata;
    description << "model " << model << " (" << metadata.input_width << "x" << metadata.input_height
                << ", trained with baseline " << metadata.baseline << " m, fx/width " << metadata.fx_over_width
                << ", " << (args.threads > 0 ? std::to_string(args.threads) : std::string("all")) << " thread(s))";
    out.source = std::move(network);
  }
  // Model or files, the work runs on a worker thread so that it can overlap the
  // odometry (how much depends on dvso.prediction_timing).
  auto worker = std::make_unique<AsyncDisparitySource>(std::move(out.source));
  out.worker = worker.get();
  out.source = std::move(worker);
  description << ", virtual baseline " << out.virtual_baseline << " m";
  if (out.tuned) {
    description << " (tuned, paper 'tb', on " << out.metadata.tuned_on << "; untuned " << out.untuned_virtual_baseline
                << " m)";
  }
  out.description = description.str();
  return out;
}

}  // namespace dvso::cli
