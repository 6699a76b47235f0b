#include "core/config_yaml.h"

#include <filesystem>

namespace dvso {

YamlSection::YamlSection(YAML::Node node, std::string origin, std::string prefix)
    : node_(std::move(node)), origin_(std::move(origin)), prefix_(std::move(prefix)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    throw Error(origin_, (prefix_.empty() ? std::string("top level") : "'" + prefix_ + "'") +
                             " must be a map of key: value");
  }
}

YamlSection YamlSection::FromFile(const std::string& path) {
  RequireFile(std::filesystem::is_regular_file(path), path, "config file does not exist");
  try {
    return YamlSection(YAML::LoadFile(path), path, "");
  } catch (const YAML::Exception& e) {
    throw Error(path, std::string("invalid YAML: ") + e.what());
  }
}

YamlSection YamlSection::FromString(const std::string& text, const std::string& origin) {
  try {
    return YamlSection(YAML::Load(text), origin, "");
  } catch (const YAML::Exception& e) {
    throw Error(origin, std::string("invalid YAML: ") + e.what());
  }
}

YamlSection& YamlSection::Child(const std::string& key) {
  used_.insert(key);
  YAML::Node child = node_.IsDefined() && !node_.IsNull() ? node_[key] : YAML::Node();
  auto section = std::shared_ptr<YamlSection>(new YamlSection(child, origin_, Where(key)));
  children_.push_back(section);
  return *section;
}

bool YamlSection::Has(const std::string& key) const {
  return node_.IsDefined() && !node_.IsNull() && node_[key].IsDefined();
}

void YamlSection::RequireAllKeysUsed() const {
  if (!node_.IsDefined() || node_.IsNull()) return;
  std::string unknown;
  for (const auto& entry : node_) {
    const std::string key = entry.first.as<std::string>();
    if (used_.count(key) == 0) unknown += (unknown.empty() ? "" : ", ") + Where(key);
  }
  if (!unknown.empty()) throw Error(origin_, "unknown config key(s): " + unknown);
  for (const auto& child : children_) child->RequireAllKeysUsed();
}

}  // namespace dvso
