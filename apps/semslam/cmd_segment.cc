#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddSegmentCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("segment", "Run a segmenter on images (and score it against ground truth)");
  cmd->callback([] { throw std::runtime_error("segment: not implemented yet"); });
}

}  // namespace semslam::cli
