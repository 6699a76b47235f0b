// PLACEHOLDER until the owning issue lands: registers `dvso eval-depth` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddEvalDepthCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("eval-depth", "Depth metrics (abs rel, sq rel, RMSE, RMSE log, delta) (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso eval-depth' is not implemented yet"); });
}

}  // namespace dvso::cli
