// Split files (core/depth_split.h): the monodepth2 '<drive> <frame> <side>' format, read strictly.
#include <gtest/gtest.h>

#include <fstream>

#include "core/depth_split.h"
#include "core/error.h"
#include "core/fs_util.h"
#include "tests/temp_dir.h"

namespace dvso {
namespace {

std::string WriteFile(const testing::TempDir& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return dir / name;
}

TEST(ParseFrameNumber, ReadsOnlyNamesOfOneToTwelveDigits) {
  EXPECT_EQ(ParseFrameNumber("0000000069"), 69);
  EXPECT_EQ(ParseFrameNumber("000000"), 0);
  EXPECT_EQ(ParseFrameNumber("999999999999"), 999999999999LL);
  EXPECT_FALSE(ParseFrameNumber("").has_value());
  EXPECT_FALSE(ParseFrameNumber("1234567890123").has_value());  // 13 digits
  EXPECT_FALSE(ParseFrameNumber("-1").has_value());
  EXPECT_FALSE(ParseFrameNumber("12a").has_value());
  EXPECT_FALSE(ParseFrameNumber("te08_000001").has_value());
}

TEST(DepthSplit, ReadsEntriesInOrderSkippingBlankAndCommentLines) {
  const testing::TempDir dir("depth_split");
  const std::vector<SplitEntry> entries = ReadSplitFile(WriteFile(
      dir, "split.txt",
      "# Eigen test split\n2011_09_26/2011_09_26_drive_0002_sync 0000000069 l\n\n"
      "2011_09_26/2011_09_26_drive_0002_sync 0000000054 r\r\n2011_10_03/2011_10_03_drive_0047_sync 12 l\n"));
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_EQ(entries[0].drive, "2011_09_26/2011_09_26_drive_0002_sync");
  EXPECT_EQ(entries[0].frame, 69);
  EXPECT_EQ(entries[0].Camera(), 2);
  EXPECT_EQ(entries[1].side, 'r');
  EXPECT_EQ(entries[1].Camera(), 3);
  EXPECT_EQ(entries[2].FrameName(), "0000000012");
  EXPECT_EQ(SplitMapName(2), "000002.png");
}

TEST(DepthSplit, MalformedLinesNameTheFileAndLine) {
  const testing::TempDir dir("depth_split_errors");
  for (const char* bad : {"drive 0000000001 x\n", "drive -5 l\n", "drive 12a l\n", "drive 1 l extra\n",
                                 "drive 1\n", "drive 99999999999 l\n"}) {
    const std::string path = WriteFile(dir, "bad.txt", std::string("# header\n") + bad);
    try {
      ReadSplitFile(path);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("bad.txt"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("line 2"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(ReadSplitFile(WriteFile(dir, "empty.txt", "# nothing\n\n")), Error);
  EXPECT_THROW(ReadSplitFile(dir / "missing.txt"), Error);
}

}  // namespace
}  // namespace dvso
