#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddRouteCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("route", "Print the shortest route between two landmarks of a saved map");
  cmd->callback([] { throw std::runtime_error("route: not implemented yet"); });
}

}  // namespace semslam::cli
