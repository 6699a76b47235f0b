// Registration functions of the `dvso` subcommands, one per file in pipelines/.
// Each adds its subcommand to the app with a callback doing the work; errors
// are thrown as dvso::Error and turned into one line + exit code 1 by main().
#pragma once

#include <CLI/CLI.hpp>

namespace dvso::cli {

// Option checks with a one-line message (CLI11's own ranges print their double limits in full).
inline CLI::Validator SignCheck(bool zero_allowed) {
  const std::string rule = zero_allowed ? ">= 0" : "> 0";
  return CLI::Validator(
      [zero_allowed, rule](std::string& value) {
        double number = 0;
        const bool ok = CLI::detail::lexical_cast(value, number) && (number > 0 || (zero_allowed && number == 0));
        return ok ? std::string() : "must be " + rule + ", got " + value;
      },
      rule);
}
inline CLI::Validator Positive() { return SignCheck(/*zero_allowed=*/false); }
inline CLI::Validator NonNegative() { return SignCheck(/*zero_allowed=*/true); }

void AddDemoCommand(CLI::App& app);          // cmd_demo.cpp
void AddSimulateCommand(CLI::App& app);      // cmd_simulate.cpp
void AddEvalOdometryCommand(CLI::App& app);  // cmd_eval_odometry.cpp
void AddEvalDepthCommand(CLI::App& app);     // cmd_eval_depth.cpp
void AddOdometryCommand(CLI::App& app);      // cmd_odometry.cpp
void AddLabelsCommand(CLI::App& app);        // cmd_labels.cpp
void AddEvalLabelsCommand(CLI::App& app);    // cmd_eval_labels.cpp
void AddAblationCommand(CLI::App& app);      // cmd_ablation.cpp
void AddTuneBaselineCommand(CLI::App& app);  // cmd_tune_baseline.cpp
void AddOxtsPosesCommand(CLI::App& app);     // cmd_oxts_poses.cpp
void AddGtDepthCommand(CLI::App& app);       // cmd_gt_depth.cpp
void AddCalibrateVignetteCommand(CLI::App& app);  // cmd_calibrate_vignette.cpp
#ifdef DVSO_WITH_TORCH
void AddTrainCommand(CLI::App& app);    // torch_cmd_train.cpp
void AddExportCommand(CLI::App& app);   // torch_cmd_export.cpp
void AddPredictCommand(CLI::App& app);  // torch_cmd_predict.cpp
void AddBenchCommand(CLI::App& app);    // torch_cmd_bench.cpp
#endif

}  // namespace dvso::cli
