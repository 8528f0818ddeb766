#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddDemoCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("demo", "Run the whole pipeline on the built-in synthetic city and write every output");
  cmd->callback([] { throw std::runtime_error("demo: not implemented yet"); });
}

}  // namespace semslam::cli
