#include "core/depth_split.h"

#include <fstream>
#include <sstream>

#include "core/error.h"
#include "core/fs_util.h"

namespace dvso {

namespace {
constexpr int kRawFrameDigits = 10;  // KITTI raw file numbers: %010d
}  // namespace

std::string SplitEntry::FrameName() const { return FrameFileName(frame, "", kRawFrameDigits); }

std::string SplitMapName(int index) { return FrameFileName(index, ".png"); }

std::vector<SplitEntry> ReadSplitFile(const std::string& path) {
  std::ifstream in(path);
  RequireFile(in.good(), path, "cannot open split file");
  std::vector<SplitEntry> entries;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    SplitEntry entry;
    std::string frame, side, extra;
    const bool parsed = static_cast<bool>(fields >> entry.drive >> frame >> side) && !(fields >> extra);
    const std::string where = "line " + std::to_string(line_number) + ": ";
    RequireFile(parsed, path, where + "expected '<drive> <frame> <side>', got '" + line + "'");
    const std::optional<long long> number = ParseFrameNumber(frame);
    RequireFile(number.has_value(), path, where + "frame '" + frame + "' is not a non-negative file number");
    RequireFile(*number <= 999999999, path, where + "frame '" + frame + "' out of range");
    entry.frame = static_cast<int>(*number);
    RequireFile(side == "l" || side == "r", path, where + "side '" + side + "' is not l or r");
    entry.side = side[0];
    entries.push_back(entry);
  }
  RequireFile(!entries.empty(), path, "split file has no entries");
  return entries;
}

}  // namespace dvso
