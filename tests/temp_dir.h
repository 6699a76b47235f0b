// Scratch folders for tests. Every path lies under one root per test process,
// <temp>/dvso_tests_<pid>, which is removed when the process exits, so a test that
// stops at a failed ASSERT (or forgets to clean up) leaves nothing behind; the process
// id keeps the processes CTest runs in parallel out of each other's folders.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>

namespace dvso::testing {

// <temp>/dvso_tests_<pid>, created on first use and removed at process exit.
inline const std::filesystem::path& ScratchRoot() {
  struct Root {
    std::filesystem::path path;
    Root()
        : path(std::filesystem::temp_directory_path() / ("dvso_tests_" + std::to_string(::getpid()))) {
      std::filesystem::remove_all(path);
      std::filesystem::create_directories(path);
    }
    ~Root() {
      std::error_code ignored;  // never throw from a destructor at exit
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Root root;
  return root.path;
}

// <root>/<name>, not created (for files and folders that the code under test makes);
// whatever was there from an earlier test of this process is removed.
inline std::string ScratchPath(const std::string& name) {
  const std::filesystem::path path = ScratchRoot() / name;
  std::filesystem::remove_all(path);
  return path.string();
}

// <root>/<name> as a fresh, empty folder.
inline std::string ScratchDir(const std::string& name) {
  const std::string path = ScratchPath(name);
  std::filesystem::create_directories(path);
  return path;
}

// The whole text of a file written by the code under test ("" when it cannot be read).
inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A scratch folder for one test, removed when the test ends (and with the root at the latest).
struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name) : path(ScratchDir(name)) {}
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

}  // namespace dvso::testing
