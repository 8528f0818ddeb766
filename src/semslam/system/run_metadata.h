#pragma once
// How a run was made, for run.json ("provenance" and "config") and the report: the command line, the semslam
// version and commit, when and where it ran, and every option it used (the SLAM options after the sensor mode
// set its parts, in the format `--config` reads).

#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace semslam {

struct RunOptions;
struct SlamOptions;

// What only the caller knows: the command line and the binary's version (the library does not know its
// build).
struct RunProvenance {
  std::vector<std::string> command;  // argv, as given
  std::string version;               // e.g. "0.1.0"
  std::string commit;                // `git describe --always --dirty` at build time, or "unknown"
  std::string build_type;            // e.g. "Release"
};

// {"command", "command_line", "version", "commit", "build_type", "date" (UTC, ISO 8601), "host_cores",
// "working_directory"}.
nlohmann::json ProvenanceJson(const RunProvenance& provenance);

// A JSON file of a run folder (run.json, timing.json); InputError naming the file when it cannot be read or
// is not JSON.
nlohmann::json ReadJsonFile(const std::filesystem::path& path);

// {"sequence" (absolute), "frames" [first, end), "mode", "pacing", "segmenter", "seed", "gps", "gps_every",
// "gps_fusion", "landmarks", "map_in", "localization_only", "exclude_dynamic", "vocabulary" (resolved),
// "slam" (every SLAM option by section, as config/default.yaml)}. `slam` is the SlamSystem's effective
// options.
nlohmann::json EffectiveConfigJson(const RunOptions& options, const SlamOptions& slam, size_t end_frame);

// "semslam 0.1.0 (commit b88fce6a1c2d-dirty, Release)".
std::string VersionLine(const RunProvenance& provenance);
// The first lines of a run's log: the version line and "command: ...".
std::vector<std::string> ProvenanceLines(const RunProvenance& provenance);

// A command line as one string a POSIX shell reads back (arguments quoted where needed).
std::string ShellQuote(const std::vector<std::string>& arguments);

}  // namespace semslam
