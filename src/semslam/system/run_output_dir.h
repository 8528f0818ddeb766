#pragma once
// The output folder of a run (`--out`): made ready before the first frame, so that a folder that cannot be
// written, a full disk or a second run into the same folder stop the run at once instead of losing it at the
// end.
//
// Policy: a new or empty folder is used as it is. A folder that holds an earlier semslam run is refused
// unless `overwrite` is set, in which case everything in it is removed first (so nothing of the earlier run
// is mixed into the new outputs), but never when it holds one of the command's inputs. A non-empty folder
// that semslam did not write is always refused. While a run writes into a folder it holds a lock on
// DIR/.semslam.lock, and a second run into the same folder is refused.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace semslam {

struct OutputDirOptions {
  bool overwrite = false;
  // "run", "localize": names the command in messages.
  std::string command = "run";
  // Refuse to start with less free space than this (a run's outputs are typically a few MiB to a few
  // hundred MiB for long drives).
  std::uint64_t min_free_bytes = std::uint64_t{32} << 20;
  // Files and folders the command reads (empty paths are ignored): a folder holding one is never emptied.
  std::vector<std::filesystem::path> inputs;
};

// The lock file's name (it stays in the folder after the run and marks the folder as semslam's), and the
// log's (a folder holding only a failed command's log counts as empty).
inline constexpr const char* kOutputLockFile = ".semslam.lock";
inline constexpr const char* kOutputLogFile = "run.log";

class RunOutputDir {
 public:
  // Creates `dir` when missing, takes its lock, checks that it can be written and has room, removes the
  // temporary files of writers that died, and applies the overwrite policy above. Throws std::runtime_error
  // naming the folder and the system's reason (EACCES, ENOSPC, ...) when it cannot be used, InvalidArgument
  // when it holds an earlier run and `overwrite` is not set, holds files that are not semslam's or holds one
  // of `inputs`.
  RunOutputDir(std::filesystem::path dir, const OutputDirOptions& options = {});
  ~RunOutputDir();
  RunOutputDir(const RunOutputDir&) = delete;
  RunOutputDir& operator=(const RunOutputDir&) = delete;

  const std::filesystem::path& path() const { return dir_; }
  // Files removed because `overwrite` was set (for the log).
  size_t removed_entries() const { return removed_entries_; }

 private:
  std::filesystem::path dir_;
  int lock_fd_ = -1;
  size_t removed_entries_ = 0;
};

}  // namespace semslam
