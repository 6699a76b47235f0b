// PLACEHOLDER until the owning issue lands: registers `dvso odometry` so the CLI
// lists it, and fails loudly when run.
#include "core/error.h"
#include "pipelines/commands.h"

namespace dvso::cli {

void AddOdometryCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("odometry", "Direct sparse odometry (mono, stereo, virtual stereo) (not implemented yet)");
  cmd->allow_extras();
  cmd->callback([] { throw Error("'dvso odometry' is not implemented yet"); });
}

}  // namespace dvso::cli
