// Strict YAML loading for options structs (Basalt style: unknown keys are an
// error, so a typo never silently falls back to a default).
//
//   YamlSection s = YamlSection::FromFile(path);        // or FromString / Child
//   s.Read("num_points", &options.num_points);
//   YamlSection& tracker = s.Child("tracker");            // nested map (may be absent)
//   ...
//   s.RequireAllKeysUsed();   // throws dvso::Error naming file + unknown key(s)
#pragma once

#include <yaml-cpp/yaml.h>

#include <memory>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.h"

namespace dvso {

// yaml-cpp keeps every copy of a repeated key and node[key] answers the first, so a repeated
// `active_points:` (or a second `tracker:` section, whose keys no check would then see) is silently
// half-ignored. Throws dvso::Error(origin, ...) naming the first repeated key, at any depth.
void RequireUniqueKeys(const YAML::Node& node, const std::string& origin, const std::string& prefix = "");

// yaml-cpp reads integers with a leading 0 as octal (`0100` = 64) and accepts hex (`0x10`); a config
// value means what it says in decimal. Throws dvso::Error(origin, ...) naming `key` otherwise.
void RequireDecimalInteger(const YAML::Node& scalar, const std::string& origin, const std::string& key);

class YamlSection {
 public:
  static YamlSection FromFile(const std::string& path);
  static YamlSection FromString(const std::string& text, const std::string& origin = "<string>");

  // Reads `key` into *value when present (keeps the default otherwise).
  // Throws dvso::Error naming the origin and key on a type mismatch, and on a
  // key without a value (`max_depth:` or `~`): a forgotten value must not
  // silently mean the default.
  template <typename T>
  bool Read(const std::string& key, T* value) {
    used_.insert(key);
    const YAML::Node child = node_[key];
    if (!child.IsDefined()) return false;
    if (child.IsNull()) {
      throw Error(origin_, "key '" + Where(key) + "' has no value (give one, or remove the key for the default)");
    }
    if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) RequireDecimalInteger(child, origin_, Where(key));
    try {
      *value = child.as<T>();
    } catch (const YAML::Exception& e) {
      throw Error(origin_, "key '" + Where(key) + "': cannot read value (" + e.msg + ")");
    }
    return true;
  }

  // Nested section; an absent key yields an empty section.
  // The reference stays valid as long as this section lives.
  YamlSection& Child(const std::string& key);
  bool Has(const std::string& key) const;
  // Marks a key as handled elsewhere (e.g. a sub-map validated by another
  // module's strict loader), so RequireAllKeysUsed() does not report it.
  void MarkUsed(const std::string& key) { used_.insert(key); }
  // Throws dvso::Error naming every key of this section (and of the children
  // obtained through Child()) that no Read()/Child() asked for.
  void RequireAllKeysUsed() const;
  const std::string& origin() const { return origin_; }
  const YAML::Node& node() const { return node_; }

 private:
  YamlSection(YAML::Node node, std::string origin, std::string prefix);
  std::string Where(const std::string& key) const { return prefix_.empty() ? key : prefix_ + "." + key; }
  YAML::Node node_;
  std::string origin_, prefix_;
  std::set<std::string> used_;
  std::vector<std::shared_ptr<YamlSection>> children_;
};

}  // namespace dvso
