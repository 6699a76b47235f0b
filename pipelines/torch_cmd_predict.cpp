// PLACEHOLDER until the owning issue lands: registers `dvso predict` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddPredictCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("predict", "Predict left/right disparity maps for an image folder (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso predict' is not implemented yet"); });
}

}  // namespace dvso::cli
