#pragma once
// What every subcommand shares: quiet mode, the binary's provenance for run.json, the run.log in a run folder,
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

// Copies every log message (debug and up when -v, else info and up) to `path` while it lives, with the date.
class LogFile {
 public:
  explicit LogFile(const std::filesystem::path& path);
  ~LogFile();
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;

 private:
  std::shared_ptr<void> sink_;
};

// For a command line CLI11 rejected: "unknown option --fram: did you mean --frames?" for each unknown subcommand
// or option close to a known one ("; " between them), or "" when nothing is close.
std::string SuggestCorrections(const CLI::App& app, const std::vector<std::string>& unexpected);

// Edit distance (insertions, deletions, substitutions, transpositions of neighbours).
size_t EditDistance(const std::string& a, const std::string& b);

}  // namespace semslam::cli
