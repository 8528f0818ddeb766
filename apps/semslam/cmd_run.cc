#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddRunCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "Run SLAM (and semantics, GPS, landmarks) on a sequence");
  cmd->callback([] { throw std::runtime_error("run: not implemented yet"); });
}

}  // namespace semslam::cli
