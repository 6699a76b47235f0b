// PLACEHOLDER until the owning issue lands: registers `dvso labels` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddLabelsCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("labels", "Sparse disparity labels from stereo odometry (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso labels' is not implemented yet"); });
}

}  // namespace dvso::cli
