#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddEvalCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("eval", "Compare an estimated trajectory with the ground truth (JSON on stdout)");
  cmd->callback([] { throw std::runtime_error("eval: not implemented yet"); });
}

}  // namespace semslam::cli
