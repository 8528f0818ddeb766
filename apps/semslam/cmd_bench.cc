#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddBenchCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("bench", "Measure speed and memory end to end");
  cmd->callback([] { throw std::runtime_error("bench: not implemented yet"); });
}

}  // namespace semslam::cli
