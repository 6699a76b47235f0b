// PLACEHOLDER until the owning issue lands: registers `dvso export` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddExportCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("export", "Export a checkpoint to TorchScript (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso export' is not implemented yet"); });
}

}  // namespace dvso::cli
