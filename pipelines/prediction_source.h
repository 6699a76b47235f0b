// Wires a disparity source into `dvso odometry --mode dvso` (and ablation /
// tune-baseline): precomputed maps or a TorchScript model run online on a
// worker thread, plus the virtual baseline b_v that converts their disparities
// to inverse depth (core/disparity_conversion.h).
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "core/disparity_conversion.h"
#include "core/disparity_source.h"
#include "core/sequence.h"
#include "vo/system/odometry_options.h"

namespace dvso::cli {

// The model `dvso odometry --mode dvso` uses when none is named (relative to the source tree).
inline constexpr const char* kShippedModel = "models/stacknet_cpu_main.pt";

struct PredictionSourceArgs {
  std::string model;               // TorchScript file; "" = the shipped model (unless files are given)
  std::string disparity_left;      // folder of KITTI uint16 PNGs or a .npy stack
  std::string disparity_right;
  double virtual_baseline = 0;     // > 0 overrides b_v
  std::string schedule;            // "" = the config's dvso.prediction_timing; else keyframe-async | keyframe-blocking | speculative
  int threads = 1;                 // inference threads; 1 measured fastest next to the odometry on 2 cores (0 = cores)
  void Check() const;
};

struct PredictionSource {
  std::unique_ptr<DisparitySource> source;  // what the odometry reads (may wrap a worker)
  AsyncDisparitySource* worker = nullptr;   // the worker thread every source runs on
  double virtual_baseline = 0;              // resolved b_v for this sequence's camera (tuned when the model has one)
  double untuned_virtual_baseline = 0;      // b_v from the training baseline alone (ablation rows without tb)
  bool tuned = false;                       // virtual_baseline is the model's tuned one (paper "tb")
  ModelMetadata metadata;                   // of the model (for files: the one predict recorded, else empty)
  std::string description;                  // one line for the run header
};

// Opens the source for `sequence` and resolves b_v: --virtual-baseline, else
// from the model's training camera (ModelMetadata): the model run online, or
// for files the model `dvso predict` recorded as their maker; else (files from
// elsewhere) the sequence's own stereo baseline. Every precondition (files
// present, model loadable) is checked here, before any output is written.
PredictionSource OpenPredictionSource(const PredictionSourceArgs& args, const SequenceReader& sequence);

// `dvso predict` records in <out>/prediction_info.json the model's metadata ("model_metadata": its b_v
// for `odometry --disparity-left`) and, with --sequence, the camera pair its maps belong to.
inline constexpr const char* kPredictionInfoFile = "prediction_info.json";
// The metadata of the model that predicted the maps in `maps_dir` (predict's left/ or right/, record one
// folder up); nullopt for maps without a record or a record without it (written before session 40).
std::optional<ModelMetadata> RecordedModelMetadata(const std::string& maps_dir);
// Throws dvso::Error naming the record when the maps in `maps_dir` (predict's left/ or right/, record one
// folder up) were predicted on another pair than `pair` (the run's sequence reads); maps without a record
// are not checked.
void RequireMapsOfCameraPair(const std::string& maps_dir, CameraPair pair);

// Loads a TorchScript model as a DisparitySource (torch builds; others throw).
std::unique_ptr<DisparitySource> OpenModelDisparitySource(const std::string& path, int threads,
                                                          ModelMetadata* metadata);

// Applies what the flags say to the odometry options (b_v, prediction timing);
// when a config's dvso.virtual_baseline wins over the source's b_v, the
// source's description says so.
void ApplyPredictionSource(const PredictionSourceArgs& args, PredictionSource* source,
                           vo::OdometryOptions* options);

// Adds --model, --disparity-left/right, --virtual-baseline, --prediction-schedule,
// --inference-threads to a subcommand; `default_schedule` is what --help names as the
// schedule used when neither the flag nor a config file sets one.
void AddPredictionOptions(CLI::App* cmd, PredictionSourceArgs* args, const std::string& default_schedule);

// Copies a TorchScript model with new metadata (torch builds; others throw).
void WriteModelWithTunedBaseline(const std::string& in_path, const std::string& out_path, const ModelMetadata& metadata);

// Path of the shipped model (source tree), or "" when it is not there.
std::string ShippedModelPath();

}  // namespace dvso::cli
