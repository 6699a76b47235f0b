// PLACEHOLDER until the owning issue lands: registers `dvso train` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddTrainCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("train", "Train SimpleNet / StackNet from a YAML config (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso train' is not implemented yet"); });
}

}  // namespace dvso::cli
