// PLACEHOLDER until the owning issue lands: registers `dvso demo` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddDemoCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "Simulate a short sequence, run odometry and evaluate it (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso demo' is not implemented yet"); });
}

}  // namespace dvso::cli
