// dvso: the single command-line entry point of the toolkit.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "core/error.h"
#include "pipelines/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"dvso - Deep Virtual Stereo Odometry toolkit"};
  app.require_subcommand(1);
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
    return app.exit(e);
  } catch (const dvso::Error& e) {
    std::cerr << "dvso: error: " << e.what() << std::endl;
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "dvso: unexpected error: " << e.what() << std::endl;
    return 2;
  }
  return 0;
}
