// YAML <-> StackNetConfig. Strict: an unknown key anywhere is an error naming
// the key and the file, so a typo never silently falls back to a default.
// A config file may start from another one: `base: other.yaml` (relative to the
// file) loads that file first and lays this one over it, maps key by key, lists
// and scalars replaced whole (so an ablation states only what it changes).
#pragma once

#include <string>
#include <vector>

#include "stacknet/options.h"

namespace dvso::stacknet {

// Loads a config file and (unless check = false, for callers that override
// fields first and call Check() themselves) checks it; throws dvso::Error naming the file.
StackNetConfig LoadConfig(const std::string& path, bool check = true);
// Same from YAML text (`origin` names the source in errors).
StackNetConfig ParseConfig(const std::string& yaml_text, const std::string& origin = "<config>", bool check = true);
// `dvso train --sequence DIR...`: the default data trains on `sequences` instead of
// its own (data.sequences replaced, data.split_file cleared: a split would win).
// An error naming the stages' datasets when no stage trains on the default data,
// where the sequences would go unused (and the export would take their camera).
void SetDefaultSequences(StackNetConfig* config, const std::vector<std::string>& sequences);
// The full config (all fields, defaults included) as YAML; printed at start
// and stored in checkpoints so that export/predict rebuild the same network.
std::string ConfigToYaml(const StackNetConfig& config);

}  // namespace dvso::stacknet
