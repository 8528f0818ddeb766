#pragma once
// Each subcommand lives in its own file and registers itself on the top-level CLI11 app.
// Commands only parse arguments and wire library calls; the work is in the library.

namespace CLI {
class App;
}

namespace semslam::cli {

void AddSynthCommand(CLI::App& app);
void AddEvalCommand(CLI::App& app);

}  // namespace semslam::cli
