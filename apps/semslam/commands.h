#pragma once
// Each subcommand lives in its own file (cmd_<name>.cc) and registers itself on the top-level CLI11 app.
// Commands only parse arguments and wire library calls; the work is in the library.

namespace CLI {
class App;
}

namespace semslam::cli {

void AddDemoCommand(CLI::App& app);
void AddSynthCommand(CLI::App& app);
void AddRunCommand(CLI::App& app);
void AddLocalizeCommand(CLI::App& app);
void AddRouteCommand(CLI::App& app);
void AddEvalCommand(CLI::App& app);
void AddReportCommand(CLI::App& app);
void AddVocabCommand(CLI::App& app);
void AddSegmentCommand(CLI::App& app);
void AddBenchCommand(CLI::App& app);
void AddComposeCommand(CLI::App& app);
void AddMergeCommand(CLI::App& app);

}  // namespace semslam::cli
