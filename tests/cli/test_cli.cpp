// End-to-end checks of the `dvso` command line: usage errors and malformed
// input give one clear message and a non-zero exit, never a crash.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/dvso_cli_runner.h"

namespace fs = std::filesystem;

namespace {

using dvso::testing::CliRun;
using dvso::testing::RunDvso;

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dvso_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

}  // namespace

TEST(Cli, HelpListsEverySubcommand) {
  const CliRun r = RunDvso("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* sub : {"demo", "simulate", "eval-odometry", "eval-depth", "odometry", "labels"}) {
    EXPECT_NE(r.out.find(sub), std::string::npos) << sub;
  }
}

TEST(Cli, UnknownSubcommandFails) {
  const CliRun r = RunDvso("frobnicate");
  EXPECT_NE(r.exit_code, 0);
}

TEST(Cli, MissingTrajectoryFileIsOneClearError) {
  const std::string dir = TempDir("missing");
  const CliRun r = RunDvso("eval-odometry --gt " + dir + "/nope.txt --est " + dir + "/nope2.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("nope.txt"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("dvso: error:"), std::string::npos) << r.out;
}

TEST(Cli, MalformedTrajectoryIsOneClearError) {
  const std::string dir = TempDir("malformed");
  std::ofstream(dir + "/gt.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::ofstream(dir + "/est.txt") << "1 0 0 0 0 1 0 0 0 0 1\n";  // 11 numbers
  const CliRun r = RunDvso("eval-odometry --gt " + dir + "/gt.txt --est " + dir + "/est.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.out.find("est.txt"), std::string::npos) << r.out;
}

TEST(Cli, OdometryOnMissingSequenceFailsCleanly) {
  const std::string dir = TempDir("noseq");
  const CliRun r = RunDvso("odometry --sequence " + dir + "/absent --mode stereo --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("absent"), std::string::npos) << r.out;
  EXPECT_FALSE(fs::exists(dir + "/out/trajectory.txt"));
}
