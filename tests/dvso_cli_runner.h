// Shared by the end-to-end test suites: runs the built `dvso` binary
// (DVSO_BINARY, defined for every test target), or a project script, and captures its output.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <array>
#include <filesystem>
#include <cstdio>
#include <string>

#include "tests/temp_dir.h"

namespace dvso::testing {

struct CliRun {
  int exit_code = -1;  // -1 when the process could not be started or did not exit normally
  std::string out;     // stdout, plus stderr when merged
};

// Runs a shell command line; stderr goes into `out` when merge_stderr, else is discarded.
inline CliRun RunCommand(const std::string& command_line, bool merge_stderr = true) {
  const std::string command = command_line + (merge_stderr ? " 2>&1" : " 2>/dev/null");
  CliRun run;
  FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) return run;
  std::array<char, 4096> buffer{};
  while (std::fgets(buffer.data(), buffer.size(), pipe) != nullptr) run.out += buffer.data();
  const int status = ::pclose(pipe);
  run.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return run;
}

// Runs `dvso ARGS`; stderr goes into `out` when merge_stderr, else is discarded.
inline CliRun RunDvso(const std::string& args, bool merge_stderr = true) {
  return RunCommand(std::string(DVSO_BINARY) + " " + args, merge_stderr);
}

// Makes a fresh folder `name`_PID under the test temp dir and simulates `frames`
// small frames (320x96) into <folder>/seq with `dvso simulate` (plus
// `extra_args`). Returns the folder ("" when the simulation failed).
inline std::string FreshSimulatedSequence(const std::string& name, int frames, const std::string& extra_args = "") {
  // Under the process's scratch root (tests/temp_dir.h): CTest's parallel processes, each with its
  // own copy of a fixture, stay out of each other's folders, and the folder goes when the process ends.
  const std::string dir = ScratchDir(name);
  const CliRun sim = RunDvso("simulate --quiet --out " + dir + "/seq --count " + std::to_string(frames) +
                             " --width 320 --height 96 --texture-size 128 " + extra_args);
  return sim.exit_code == 0 ? dir : "";
}

}  // namespace dvso::testing
