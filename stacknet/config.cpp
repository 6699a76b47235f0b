#include "stacknet/config.h"

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <type_traits>

#include "core/config_yaml.h"
#include "core/error.h"

namespace dvso::stacknet {
namespace {

// Reads the fields of one YAML map; Finish() rejects keys nobody asked for.
class StrictMap {
 public:
  StrictMap(const YAML::Node& node, std::string where) : node_(node), where_(std::move(where)) {
    Require(!node_ || node_.IsNull() || node_.IsMap(), where_ + " must be a map");
  }
  template <typename T>
  void Get(const std::string& key, T* value) {
    seen_.insert(key);
    if (!node_ || node_.IsNull() || !node_[key]) return;
    // yaml-cpp reads an empty value (`output_dir:` or `~`) as the string "null": a forgotten value must
    // neither become that folder nor silently mean the default (as core/config_yaml.h YamlSection::Read).
    Require(!node_[key].IsNull(), where_ + "." + key + ": has no value (give one, or remove the key for the default)");
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) RequireDecimalInteger(node_[key], "", where_ + "." + key);
    try {
      *value = node_[key].as<T>();
    } catch (const YAML::Exception& e) {
      throw Error(where_ + "." + key + ": bad value (" + e.msg + ")");
    }
  }
  YAML::Node Child(const std::string& key) {
    seen_.insert(key);
    if (!node_ || node_.IsNull()) return YAML::Node();
    return node_[key];
  }
  void Finish() const {
    if (!node_ || node_.IsNull()) return;
    for (const auto& item : node_) {
      const std::string key = item.first.as<std::string>();
      Require(seen_.count(key) > 0, "unknown config key '" + where_ + "." + key + "'");
    }
  }

 private:
  YAML::Node node_;
  std::string where_;
  std::set<std::string> seen_;
};

template <typename Options, typename Visit>
void ReadSection(const YAML::Node& node, const std::string& where, Options* options, Visit visit) {
  StrictMap map(node, where);
  visit(map, *options);
  map.Finish();
}

// One visitor per struct, used for both reading and writing (same key list).
template <typename Map>
void VisitNetwork(Map& m, NetworkOptions& o) {
  m.Get("encoder_depth", &o.encoder_depth);
  m.Get("width_multiplier", &o.width_multiplier);
  m.Get("input_height", &o.input_height);
  m.Get("input_width", &o.input_width);
  m.Get("max_disparity", &o.max_disparity);
  m.Get("residual_leaky_slope", &o.residual_leaky_slope);
  m.Get("residual_blocks", &o.residual_blocks);
  m.Get("normalization", &o.normalization);
  m.Get("initial_disparity", &o.initial_disparity);
  m.Get("standardize_residual_inputs", &o.standardize_residual_inputs);
}
template <typename Map>
void VisitLoss(Map& m, LossOptions& o) {
  m.Get("alpha_u", &o.alpha_u);
  m.Get("alpha_s", &o.alpha_s);
  m.Get("alpha_lr", &o.alpha_lr);
  m.Get("alpha_smooth", &o.alpha_smooth);
  m.Get("alpha_occ", &o.alpha_occ);
  m.Get("ssim_alpha", &o.ssim_alpha);
  m.Get("berhu_fraction", &o.berhu_fraction);
  m.Get("relative_supervision", &o.relative_supervision);
  m.Get("num_scales", &o.num_scales);
}
template <typename Map>
void VisitData(Map& m, DataOptions& o) {
  m.Get("sequences", &o.sequences);
  m.Get("split_file", &o.split_file);
  m.Get("split_root", &o.split_root);
  m.Get("label_dir_left", &o.label_dir_left);
  m.Get("label_dir_right", &o.label_dir_right);
  m.Get("gt_disparity_left", &o.gt_disparity_left);
  m.Get("gt_disparity_right", &o.gt_disparity_right);
  m.Get("gt_sample_fraction", &o.gt_sample_fraction);
  m.Get("frame_step", &o.frame_step);
  m.Get("use_color", &o.use_color);
}
template <typename Map>
void VisitAugment(Map& m, AugmentOptions& o) {
  m.Get("enabled", &o.enabled);
  m.Get("probability", &o.probability);
  m.Get("gamma_min", &o.gamma_min);
  m.Get("gamma_max", &o.gamma_max);
  m.Get("brightness_min", &o.brightness_min);
  m.Get("brightness_max", &o.brightness_max);
  m.Get("color_min", &o.color_min);
  m.Get("color_max", &o.color_max);
  m.Get("flip_probability", &o.flip_probability);
  m.Get("grey_probability", &o.grey_probability);
}
template <typename Map>
void VisitTrain(Map& m, TrainOptions& o) {
  m.Get("output_dir", &o.output_dir);
  m.Get("batch_size", &o.batch_size);
  m.Get("num_workers", &o.num_workers);
  m.Get("seed", &o.seed);
  m.Get("adam_beta1", &o.adam_beta1);
  m.Get("adam_beta2", &o.adam_beta2);
  m.Get("adam_epsilon", &o.adam_epsilon);
  m.Get("device", &o.device);
  m.Get("num_threads", &o.num_threads);
  m.Get("progress", &o.progress);
  m.Get("init_from", &o.init_from);
}
template <typename Map>
void VisitStage(Map& m, StageOptions& o) {
  m.Get("name", &o.name);
  m.Get("model", &o.model);
  m.Get("epochs", &o.epochs);
  m.Get("learning_rate", &o.learning_rate);
  m.Get("lr_halving_start", &o.lr_halving_start);
  m.Get("lr_halving_every", &o.lr_halving_every);
  m.Get("use_unsupervised", &o.use_unsupervised);
  m.Get("use_supervised", &o.use_supervised);
  m.Get("use_lr", &o.use_lr);
  m.Get("use_smooth", &o.use_smooth);
  m.Get("use_occ", &o.use_occ);
  m.Get("data", &o.data);
  m.Get("max_steps_per_epoch", &o.max_steps_per_epoch);
}

// Writer with the same Get() interface as StrictMap.
class YamlWriter {
 public:
  explicit YamlWriter(YAML::Emitter& out) : out_(out) {}
  template <typename T>
  void Get(const std::string& key, T* value) {
    out_ << YAML::Key << key << YAML::Value << *value;
  }

 private:
  YAML::Emitter& out_;
};

template <typename Options, typename Visit>
void WriteSection(YAML::Emitter& out, const std::string& key, Options options, Visit visit) {
  out << YAML::Key << key << YAML::Value << YAML::BeginMap;
  YamlWriter writer(out);
  visit(writer, options);
  out << YAML::EndMap;
}

StackNetConfig ParseNode(const YAML::Node& root, const std::string& origin) {
  StackNetConfig config;
  StrictMap top(root, "config");
  ReadSection(top.Child("network"), "network", &config.network, VisitNetwork<StrictMap>);
  ReadSection(top.Child("loss"), "loss", &config.loss, VisitLoss<StrictMap>);
  ReadSection(top.Child("data"), "data", &config.data, VisitData<StrictMap>);
  ReadSection(top.Child("augment"), "augment", &config.augment, VisitAugment<StrictMap>);
  ReadSection(top.Child("train"), "train", &config.train, VisitTrain<StrictMap>);
  const YAML::Node datasets = top.Child("datasets");
  if (datasets && !datasets.IsNull()) {
    Require(datasets.IsMap(), "config.datasets must be a map of name -> data options");
    for (const auto& item : datasets) {
      const std::string name = item.first.as<std::string>();
      DataOptions options = config.data;  // named datasets inherit the default data options
      options.sequences.clear();
      options.split_file.clear();
      ReadSection(item.second, "datasets." + name, &options, VisitData<StrictMap>);
      config.datasets.emplace_back(name, options);
    }
  }
  const YAML::Node stages = top.Child("stages");
  if (stages && !stages.IsNull()) {
    Require(stages.IsSequence(), "config.stages must be a list");
    for (size_t i = 0; i < stages.size(); ++i) {
      StageOptions stage;
      stage.name = "stage" + std::to_string(i);
      ReadSection(stages[i], "stages[" + std::to_string(i) + "]", &stage, VisitStage<StrictMap>);
      config.stages.push_back(stage);
    }
  }
  top.Finish();
  return config;
}

StackNetConfig FromNode(const YAML::Node& root, const std::string& origin, bool check) {
  try {
    StackNetConfig config = ParseNode(root, origin);
    if (check) config.Check();
    return config;
  } catch (const Error& e) {
    if (!e.path().empty()) throw;
    throw Error(origin, e.what());
  }
}

YAML::Node ParseYaml(const std::string& yaml_text, const std::string& origin) {
  try {
    YAML::Node root = YAML::Load(yaml_text);
    RequireUniqueKeys(root, origin);
    return root;
  } catch (const YAML::Exception& e) {
    throw Error(origin, std::string("YAML parse error: ") + e.what());
  }
}

// `over` laid onto `base`: maps merge key by key (recursively), anything else
// (scalars, lists such as `stages` or `sequences`) replaces the base's value.
// An empty section (`train:` with every line commented out) leaves the base's
// map as it is instead of resetting it to the built-in defaults.
YAML::Node MergeOnto(const YAML::Node& base, const YAML::Node& over) {
  if (base.IsMap() && over.IsNull()) return YAML::Clone(base);
  if (!base.IsMap() || !over.IsMap()) return YAML::Clone(over);
  YAML::Node merged = YAML::Clone(base);
  for (const auto& item : over) {
    Require(item.first.IsScalar(), "config keys must be plain names");
    const std::string key = item.first.as<std::string>();
    const YAML::Node base_value = base[key];
    merged[key] = base_value ? MergeOnto(base_value, item.second) : YAML::Clone(item.second);
  }
  return merged;
}

// A chain of `base:` files longer than this is taken for a cycle.
constexpr int kMaxBaseChain = 8;

// The YAML of a config file with its `base:` chain resolved (base paths are
// relative to the file that names them).
YAML::Node LoadResolvedYaml(const std::string& path, int chain_length) {
  Require(chain_length < kMaxBaseChain,
          "config 'base:' chain longer than " + std::to_string(kMaxBaseChain) + " files (a cycle?) at " + path);
  std::ifstream file(path);
  RequireFile(file.good(), path, "cannot open config file");
  std::stringstream text;
  text << file.rdbuf();
  YAML::Node root = ParseYaml(text.str(), path);
  if (!root.IsMap() || !root["base"]) return root;
  const YAML::Node base_key = root["base"];
  RequireFile(base_key.IsScalar() && !base_key.as<std::string>().empty(), path, "'base' must name a config file");
  const std::filesystem::path base_path =
      std::filesystem::path(path).parent_path() / base_key.as<std::string>();
  root.remove("base");
  YAML::Node base_root = LoadResolvedYaml(base_path.string(), chain_length + 1);
  try {
    ParseNode(base_root, base_path.string());  // a key error in the base names the base file
  } catch (const Error& e) {
    if (!e.path().empty()) throw;
    throw Error(base_path.string(), e.what());
  }
  return MergeOnto(base_root, root);
}

}  // namespace

StackNetConfig ParseConfig(const std::string& yaml_text, const std::string& origin, bool check) {
  const YAML::Node root = ParseYaml(yaml_text, origin);
  if (root.IsMap() && root["base"]) {
    throw Error(origin, "'base:' is resolved only when a config is loaded from a file (LoadConfig)");
  }
  return FromNode(root, origin, check);
}

StackNetConfig LoadConfig(const std::string& path, bool check) {
  return FromNode(LoadResolvedYaml(path, 0), path, check);
}

void SetDefaultSequences(StackNetConfig* config, const std::vector<std::string>& sequences) {
  std::string datasets;  // the named datasets the stages use, when none uses the default data
  bool default_used = config->stages.empty();  // no stages: Check() says so
  for (const StageOptions& stage : config->stages) {
    default_used = default_used || stage.data.empty();
    if (!stage.data.empty() && datasets.find("'" + stage.data + "'") == std::string::npos) {
      datasets += (datasets.empty() ? "'" : ", '") + stage.data + "'";
    }
  }
  Require(default_used, "--sequence replaces data.sequences, but no stage trains on `data:` (the stages use "
                        "dataset(s) " + datasets + "): set their sequences in the config instead");
  config->data.sequences = sequences;
  config->data.split_file.clear();
}

std::string ConfigToYaml(const StackNetConfig& config) {
  YAML::Emitter out;
  out << YAML::BeginMap;
  WriteSection(out, "network", config.network, VisitNetwork<YamlWriter>);
  WriteSection(out, "loss", config.loss, VisitLoss<YamlWriter>);
  WriteSection(out, "data", config.data, VisitData<YamlWriter>);
  WriteSection(out, "augment", config.augment, VisitAugment<YamlWriter>);
  WriteSection(out, "train", config.train, VisitTrain<YamlWriter>);
  if (!config.datasets.empty()) {
    out << YAML::Key << "datasets" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, options] : config.datasets) WriteSection(out, name, options, VisitData<YamlWriter>);
    out << YAML::EndMap;
  }
  out << YAML::Key << "stages" << YAML::Value << YAML::BeginSeq;
  for (StageOptions stage : config.stages) {
    out << YAML::BeginMap;
    YamlWriter writer(out);
    VisitStage(writer, stage);
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

}  // namespace dvso::stacknet
