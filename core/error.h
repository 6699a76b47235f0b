// Errors raised by every dvso module. One exception type, always carrying the
// offending path when there is one, so the CLI can print a single clear line
// ("dvso: error: <file>: <what>") and exit non-zero.
#pragma once

#include <stdexcept>
#include <string>

namespace dvso {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
  Error(const std::string& path, const std::string& message)
      : std::runtime_error(path + ": " + message), path_(path) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// Throws dvso::Error(message) when the condition is false. Used for user input
// and option validation; programming errors use assert.
inline void Require(bool condition, const std::string& message) {
  if (!condition) throw Error(message);
}
inline void RequireFile(bool condition, const std::string& path, const std::string& message) {
  if (!condition) throw Error(path, message);
}

}  // namespace dvso
