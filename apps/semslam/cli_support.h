#pragma once
// What every subcommand shares: quiet mode, the binary's provenance for run.json and log files,
// and "did you mean" suggestions for a mistyped command line.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "semslam/system/run_metadata.h"

namespace CLI {
class App;
}

namespace semslam::cli {

// -q before or after the subcommand: only errors are logged and no progress lines are printed (results a command
// prints on stdout, such as eval's JSON, are unchanged).
bool Quiet();
void SetQuiet(bool quiet);

// "semslam 0.1.0 (commit b88fce6a1c2d-dirty, Release)".
std::string VersionLine();
// The command line of this process and the binary's version, set by main.
const RunProvenance& Provenance();
void SetCommandLine(int argc, char** argv);

// The first lines of a log file (core/log_file.h): the version and the command line.
std::vector<std::string> LogHeader();

// For a command line CLI11 rejected: "unknown option --fram: did you mean --frames?" for each unknown subcommand
// or option close to a known one ("; " between them), or "" when nothing is close.
std::string SuggestCorrections(const CLI::App& app, const std::vector<std::string>& unexpected);

// The options `run` and `localize` share: --camera, and the output folder's --out, --overwrite and
// --max-bad-frames.
struct CameraAndOutputArgs {
  std::string camera;
  std::string out;
  bool overwrite = false;
  size_t max_bad_frames = 10;
};
void AddCameraAndOutputOptions(CLI::App& cmd, CameraAndOutputArgs& args);

// Edit distance (insertions, deletions, substitutions, transpositions of neighbours).
size_t EditDistance(const std::string& a, const std::string& b);

}  // namespace semslam::cli
