#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddVocabCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("vocab", "Train or convert a bag-of-words vocabulary");
  cmd->callback([] { throw std::runtime_error("vocab: not implemented yet"); });
}

}  // namespace semslam::cli
