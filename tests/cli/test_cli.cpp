// End-to-end checks of the `dvso` command line: usage errors and malformed
// input give one clear message and a non-zero exit, never a crash.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace fs = std::filesystem;

namespace {

struct RunResult {
  int exit_code;
  std::string output;  // stdout + stderr
};

RunResult RunDvso(const std::string& args) {
  const std::string command = std::string(DVSO_BINARY) + " " + args + " 2>&1";
  RunResult result{-1, ""};
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return result;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) result.output += buffer.data();
  const int status = ::pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

std::string TempDir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("dvso_cli_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

}  // namespace

TEST(Cli, HelpListsEverySubcommand) {
  const RunResult r = RunDvso("--help");
  EXPECT_EQ(r.exit_code, 0);
  for (const char* sub : {"demo", "simulate", "eval-odometry", "eval-depth", "odometry", "labels"}) {
    EXPECT_NE(r.output.find(sub), std::string::npos) << sub;
  }
}

TEST(Cli, UnknownSubcommandFails) {
  const RunResult r = RunDvso("frobnicate");
  EXPECT_NE(r.exit_code, 0);
}

TEST(Cli, MissingTrajectoryFileIsOneClearError) {
  const std::string dir = TempDir("missing");
  const RunResult r = RunDvso("eval-odometry --gt " + dir + "/nope.txt --est " + dir + "/nope2.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("nope.txt"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("dvso: error:"), std::string::npos) << r.output;
}

TEST(Cli, MalformedTrajectoryIsOneClearError) {
  const std::string dir = TempDir("malformed");
  std::ofstream(dir + "/gt.txt") << "1 0 0 0 0 1 0 0 0 0 1 0\n";
  std::ofstream(dir + "/est.txt") << "1 0 0 0 0 1 0 0 0 0 1\n";  // 11 numbers
  const RunResult r = RunDvso("eval-odometry --gt " + dir + "/gt.txt --est " + dir + "/est.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("est.txt"), std::string::npos) << r.output;
}

TEST(Cli, OdometryOnMissingSequenceFailsCleanly) {
  const std::string dir = TempDir("noseq");
  const RunResult r = RunDvso("odometry --sequence " + dir + "/absent --mode stereo --out " + dir + "/out");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("absent"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir + "/out/trajectory.txt"));
}
