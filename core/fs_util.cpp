#include "core/fs_util.h"

#include <cstdio>
#include <filesystem>
#include <system_error>

#include "core/error.h"

namespace dvso {

void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  // Keep the extension last so that writers choosing a format by extension
  // (cv::imwrite) still work on the temporary file.
  const fs::path temp =
      target.parent_path() / (target.stem().string() + ".tmp-writing" + target.extension().string());
  try {
    write(temp.string());
  } catch (...) {
    std::error_code ec;
    fs::remove(temp, ec);
    throw;
  }
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) {
    fs::remove(temp, ec);
    throw Error(path, "cannot move the finished file into place");
  }
}

void EnsureDirectory(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  RequireFile(!ec && std::filesystem::is_directory(path), path, "cannot create directory");
}

std::string JoinPath(const std::string& a, const std::string& b) {
  return (std::filesystem::path(a) / b).string();
}

std::string FrameFileName(int index, const std::string& extension, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%0*d", digits, index);
  return std::string(buf) + extension;
}

std::optional<long long> ParseFrameNumber(const std::string& name) {
  constexpr size_t kMaxDigits = 12;  // fits a long long with room to spare
  if (name.empty() || name.size() > kMaxDigits || name.find_first_not_of("0123456789") != std::string::npos) {
    return std::nullopt;
  }
  return std::stoll(name);
}

}  // namespace dvso
