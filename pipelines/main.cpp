// dvso: the single command-line entry point of the toolkit.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>
#include <string>

#include "core/error.h"
#include "core/simulator.h"
#include "pipelines/commands.h"

namespace {

// Exit statuses: 0 success (and --help), then one per kind of failure (and 130 after Ctrl-C, as shells use).
constexpr int kExitError = 1;       // dvso::Error: bad input or a failed run, one line naming the file
constexpr int kExitUsage = 2;       // the command line itself (unknown option, missing or invalid flag value)
constexpr int kExitUnexpected = 3;  // anything else (a bug): reported, never a crash

// CLI11's own report is two lines ("<what>" then "Run with --help ..."); ours is the one-line form of every
// other dvso error, naming the subcommand whose --help lists the options.
// CLI11 calls a mistyped subcommand "A subcommand is required"; first_argument names it instead.
int ReportUsageError(const CLI::App& app, const CLI::ParseError& error, const std::string& first_argument) {
  std::string command = "dvso";
  for (const CLI::App* sub : app.get_subcommands()) command += " " + sub->get_name();
  std::string what = error.what();
  if (app.get_subcommands().empty() && !first_argument.empty() && first_argument[0] != '-') {
    what = "unknown subcommand '" + first_argument + "'";
  }
  for (char& c : what) {
    if (c == '\n') c = ' ';
  }
  std::cerr << "dvso: error: " << what << " (see " << command << " --help)" << std::endl;
  return kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"dvso - Deep Virtual Stereo Odometry toolkit"};
  app.require_subcommand(1);
  // The simulator's world version lets scripts that cache rendered worlds tell a stale one (core/simulator.h).
  app.set_version_flag("--version", std::string("dvso ") + DVSO_VERSION + " (simulator world version " +
                                        std::to_string(dvso::kSimulatorWorldVersion) + ")");
  app.set_help_all_flag("--help-all", "Show help for every subcommand");
  dvso::cli::AddDemoCommand(app);
  dvso::cli::AddSimulateCommand(app);
  dvso::cli::AddEvalOdometryCommand(app);
  dvso::cli::AddEvalDepthCommand(app);
  dvso::cli::AddOdometryCommand(app);
  dvso::cli::AddLabelsCommand(app);
  dvso::cli::AddEvalLabelsCommand(app);
  dvso::cli::AddAblationCommand(app);
  dvso::cli::AddTuneBaselineCommand(app);
  dvso::cli::AddOxtsPosesCommand(app);
  dvso::cli::AddGtDepthCommand(app);
  dvso::cli::AddCalibrateVignetteCommand(app);
#ifdef DVSO_WITH_TORCH
  dvso::cli::AddTrainCommand(app);
  dvso::cli::AddExportCommand(app);
  dvso::cli::AddPredictCommand(app);
  dvso::cli::AddBenchCommand(app);
#endif
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);  // --help, --help-all, --version
    return ReportUsageError(app, e, argc > 1 ? argv[1] : "");
  } catch (const dvso::Error& e) {
    std::cerr << "dvso: error: " << e.what() << std::endl;
    return kExitError;
  } catch (const std::exception& e) {
    std::cerr << "dvso: unexpected error: " << e.what() << std::endl;
    return kExitUnexpected;
  }
  return 0;
}
