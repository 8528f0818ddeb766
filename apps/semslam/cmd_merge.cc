// semslam merge --maps RUN_DIR... --out DIR: the maps of several runs (drives) merged into one map, one
// session per drive, written as a run folder (system/session_merge.h).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli_support.h"
#include "commands.h"
#include "semslam/system/session_merge.h"

namespace semslam::cli {
namespace {

struct MergeArgs {
  std::vector<std::string> maps;
  std::string out;
  bool overwrite = false;
  std::string vocabulary;
  bool no_place_recognition = false;
  bool no_drive_loops = false;
  bool no_global_ba = false;
  bool no_gps_fusion = false;
  int global_ba_window = 1000;
  bool quiet = false;
};

void Run(const MergeArgs& args) {
  SessionMergeOptions options;
  for (const std::string& m : args.maps) options.runs.emplace_back(m);
  options.output = args.out;
  options.overwrite = args.overwrite;
  options.vocabulary = args.vocabulary;
  options.place_recognition = !args.no_place_recognition;
  options.loops_between_drives = !args.no_drive_loops;
  options.global_ba = !args.no_global_ba;
  options.gps_fusion = !args.no_gps_fusion;
  options.global_ba_window_keyframes = args.global_ba_window;
  options.show_progress = !args.quiet && !Quiet();
  options.provenance = Provenance();
  const SessionMergeSummary summary = MergeSessions(options);
  std::printf(
      "%zu sessions merged into %zu map%s (%zu by place recognition, %zu by GPS; %zu loops between "
      "drives) in %.1f s\n",
      summary.sessions, summary.maps, summary.maps == 1 ? "" : "s", summary.place_merges, summary.gps_joins,
      summary.session_loops, summary.seconds);
}

}  // namespace

void AddMergeCommand(CLI::App& app) {
  auto args = std::make_shared<MergeArgs>();
  auto* cmd = app.add_subcommand("merge",
                                 "Merge the maps of several runs (drives) into one map, a session per drive");
  cmd->add_option("--maps", args->maps,
                  "Run folders (each with map.semslam and run.json), or earlier merges' outputs")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", args->out, "Output folder (a run folder)")->required();
  cmd->add_flag("--overwrite", args->overwrite, "Replace an earlier run's outputs in the output folder");
  cmd->add_option("--vocabulary", args->vocabulary, "Bag-of-words vocabulary")->check(CLI::ExistingFile);
  cmd->add_flag("--no-place-recognition", args->no_place_recognition,
                "Join maps by their GPS placement only (no search for shared places)");
  cmd->add_flag("--no-drive-loops", args->no_drive_loops,
                "Tie drives of a merged map only where a merge joined them (no loops between drives)");
  cmd->add_flag("--no-global-ba", args->no_global_ba, "Skip the final bundle adjustment of the merged maps");
  cmd->add_flag("--no-gps-fusion", args->no_gps_fusion,
                "Keep the merged map where the merges put it (do not fuse it with every drive's GPS log)");
  cmd->add_option("--global-ba-window", args->global_ba_window,
                  "Keyframes one bundle adjustment optimizes together at most (bounds memory)")
      ->capture_default_str()
      ->check(CLI::Range(2, 1'000'000));
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr (no log messages, no progress lines)");
  cmd->callback([args] { Run(*args); });
}

}  // namespace semslam::cli
