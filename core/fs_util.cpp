#include "core/fs_util.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <system_error>
#include <vector>

#include "core/error.h"

namespace dvso {

void WriteAtomically(const std::string& path,
                     const std::function<void(const std::string&)>& write) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  // Keep the extension last so that writers choosing a format by extension
  // (cv::imwrite) still work on the temporary file.
  const fs::path temp =
      target.parent_path() / (target.stem().string() + kAtomicWriteTag + target.extension().string());
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

void WriteStreamAtomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary) {
  WriteAtomically(path, [&](const std::string& temp) {
    std::ofstream out(temp, binary ? std::ios::out | std::ios::binary : std::ios::out);
    RequireFile(out.is_open(), path, "cannot create the file");
    write(out);
    out.close();  // flushes: the last buffered bytes are written only here
    RequireFile(!out.fail(), path, "write failed (disk full?)");
  });
}

bool IsUnfinishedAtomicWrite(const std::filesystem::path& path) {
  // "000001.tmp-writing.png", or "INTERRUPTED.tmp-writing" for a target without an extension.
  if (path.extension() == kAtomicWriteTag) return true;
  const std::string stem = path.stem().string();
  const std::string tag = kAtomicWriteTag;
  return stem.size() >= tag.size() && stem.compare(stem.size() - tag.size(), tag.size(), tag) == 0;
}

void RemoveUnfinishedAtomicWrites(const std::string& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) return;
  std::vector<fs::path> leftovers;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.is_regular_file() && IsUnfinishedAtomicWrite(entry.path())) leftovers.push_back(entry.path());
  }
  for (const fs::path& path : leftovers) fs::remove(path);
}

void EnsureDirectory(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  RequireFile(!ec && std::filesystem::is_directory(path), path, "cannot create directory");
}

std::filesystem::path NormalizedFolderPath(const std::string& path) {
  std::filesystem::path p = std::filesystem::absolute(path).lexically_normal();
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();  // "a/drive/" -> "a/drive"
  return p;
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
