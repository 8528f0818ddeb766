#include <CLI/CLI.hpp>

#include <stdexcept>

#include "commands.h"

namespace semslam::cli {

void AddSynthCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("synth", "Render the synthetic city as a KITTI-layout dataset with ground truth");
  cmd->callback([] { throw std::runtime_error("synth: not implemented yet"); });
}

}  // namespace semslam::cli
