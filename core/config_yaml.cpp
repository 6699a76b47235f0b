#include "core/config_yaml.h"

#include <filesystem>
#include <set>

namespace dvso {

void RequireUniqueKeys(const YAML::Node& node, const std::string& origin, const std::string& prefix) {
  if (node.IsMap()) {
    std::set<std::string> keys;
    for (const auto& entry : node) {
      const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : std::string("<complex key>");
      const std::string where = prefix.empty() ? key : prefix + "." + key;
      if (!keys.insert(key).second) throw Error(origin, "config key '" + where + "' appears twice");
      RequireUniqueKeys(entry.second, origin, where);
    }
  } else if (node.IsSequence()) {
    for (size_t i = 0; i < node.size(); ++i) {
      RequireUniqueKeys(node[i], origin, prefix + "[" + std::to_string(i) + "]");
    }
  }
}

void RequireDecimalInteger(const YAML::Node& scalar, const std::string& origin, const std::string& key) {
  if (!scalar.IsScalar()) return;  // as<T>() reports the type mismatch
  std::string text = scalar.Scalar();
  if (!text.empty() && (text[0] == '+' || text[0] == '-')) text.erase(0, 1);
  const bool octal = text.size() > 1 && text[0] == '0' &&
                     text.find_first_not_of("0123456789") == std::string::npos;
  const bool hex = text.size() > 2 && text[0] == '0' && (text[1] == 'x' || text[1] == 'X');
  if (octal || hex) {  // anything else that is no integer (0.5) is reported by the conversion
    const std::string message = "key '" + key + "': '" + scalar.Scalar() +
                                "' is not a decimal integer (YAML would read a leading 0 as octal, 0x as hex)";
    throw origin.empty() ? Error(message) : Error(origin, message);
  }
}

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
    YAML::Node root = YAML::LoadFile(path);
    RequireUniqueKeys(root, path);
    return YamlSection(root, path, "");
  } catch (const YAML::Exception& e) {
    throw Error(path, std::string("invalid YAML: ") + e.what());
  }
}

YamlSection YamlSection::FromString(const std::string& text, const std::string& origin) {
  try {
    YAML::Node root = YAML::Load(text);
    RequireUniqueKeys(root, origin);
    return YamlSection(root, origin, "");
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
