// PLACEHOLDER until the owning issue lands: registers `dvso simulate` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddSimulateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("simulate", "Render a synthetic KITTI-like stereo sequence with exact ground truth (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso simulate' is not implemented yet"); });
}

}  // namespace dvso::cli
