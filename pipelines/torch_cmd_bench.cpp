// PLACEHOLDER until the owning issue lands: registers `dvso bench` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddBenchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("bench", "Inference latency of a TorchScript model (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso bench' is not implemented yet"); });
}

}  // namespace dvso::cli
