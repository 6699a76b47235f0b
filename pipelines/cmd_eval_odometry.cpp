// PLACEHOLDER until the owning issue lands: registers `dvso eval-odometry` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddEvalOdometryCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("eval-odometry", "KITTI odometry metrics (t_rel, r_rel), ATE and RPE (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso eval-odometry' is not implemented yet"); });
}

}  // namespace dvso::cli
