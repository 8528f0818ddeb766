#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddLocalizeCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("localize", "Relocalize a sequence against a saved map without GPS");
  cmd->callback([] { throw std::runtime_error("localize: not implemented yet"); });
}

}  // namespace semslam::cli
