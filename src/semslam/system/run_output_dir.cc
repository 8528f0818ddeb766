#include "semslam/system/run_output_dir.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <vector>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

// The files whose presence says that an earlier semslam command wrote the folder.
bool HoldsSemslamOutputs(const fs::path& dir, bool had_lock_file) {
  std::error_code ec;
  return had_lock_file || fs::exists(dir / "run.json", ec) || fs::exists(dir / "localize.json", ec) ||
         fs::exists(dir / "map.semslam", ec) || fs::exists(dir / "trajectory.tum", ec);
}

// The first of `inputs` that lies in `dir` (or is `dir`), compared by their absolute, normalized paths.
std::optional<fs::path> InputInside(const fs::path& dir, const std::vector<fs::path>& inputs) {
  std::error_code ec;
  const fs::path folder = fs::weakly_canonical(dir, ec);
  if (ec) return std::nullopt;
  for (const fs::path& input : inputs) {
    if (input.empty()) continue;
    const fs::path path = fs::weakly_canonical(input, ec);
    if (ec) continue;
    const auto [folder_end, path_end] = std::mismatch(folder.begin(), folder.end(), path.begin(), path.end());
    if (folder_end == folder.end()) return input;
  }
  return std::nullopt;
}

std::string ReadSmallFile(int fd) {
  char buffer[256];
  const ssize_t n = ::pread(fd, buffer, sizeof(buffer) - 1, 0);
  return n > 0 ? std::string(buffer, static_cast<size_t>(n)) : std::string();
}

}  // namespace

RunOutputDir::RunOutputDir(fs::path dir, const OutputDirOptions& options) : dir_(std::move(dir)) {
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec)) {
    throw std::runtime_error(SystemErrorMessage(dir_, "cannot use as the output folder", ENOTDIR));
  }
  fs::create_directories(dir_, ec);
  if (ec) throw std::runtime_error(SystemErrorMessage(dir_, "cannot create the output folder", ec.value()));

  // The lock: writable folder, and one writer at a time.
  const fs::path lock_path = dir_ / kOutputLockFile;
  const bool had_lock_file = fs::exists(lock_path, ec);
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) {
    throw std::runtime_error(SystemErrorMessage(dir_, "cannot write into the output folder", errno));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    std::string holder = ReadSmallFile(lock_fd_);
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == '\0')) holder.pop_back();
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (error == EWOULDBLOCK) {
      throw std::runtime_error(fmt::format(
          "{}: another semslam command is writing into this folder{}; wait for it to end or choose another "
          "--out",
          dir_.string(), holder.empty() ? "" : " (" + holder + ")"));
    }
    throw std::runtime_error(SystemErrorMessage(lock_path, "cannot lock", error));
  }
  // Who holds it, for the message above; writing it also proves that the disk takes data.
  const std::string holder =
      fmt::format("pid {}, semslam {}\n", static_cast<long>(::getpid()), options.command);
  if (::ftruncate(lock_fd_, 0) != 0 ||
      ::pwrite(lock_fd_, holder.data(), holder.size(), 0) != static_cast<ssize_t>(holder.size()) ||
      ::fsync(lock_fd_) != 0) {
    const int error = errno != 0 ? errno : EIO;
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw std::runtime_error(SystemErrorMessage(dir_, "cannot write into the output folder", error));
  }

  struct statvfs space {};
  if (::statvfs(dir_.c_str(), &space) == 0) {
    const std::uint64_t free_bytes = std::uint64_t{space.f_bavail} * space.f_frsize;
    if (free_bytes < options.min_free_bytes) {
      ::close(lock_fd_);
      lock_fd_ = -1;
      throw std::runtime_error(fmt::format(
          "{}: {}: {:.1f} MiB free, a {} needs at least {} MiB", dir_.string(), std::strerror(ENOSPC),
          static_cast<double>(free_bytes) / (1 << 20), options.command, options.min_free_bytes >> 20));
    }
  }

  // Leftovers of a writer that was killed, then the earlier run itself.
  if (const size_t stale = RemoveStaleTempFiles(dir_); stale > 0) {
    spdlog::info("{}: removed {} temporary file(s) left by an earlier run that was killed", dir_.string(),
                 stale);
  }
  std::vector<fs::path> entries;
  for (const auto& entry : fs::directory_iterator(dir_, ec)) {
    // A command that failed before its first output left only its log (written again by this one).
    if (entry.path().filename() != kOutputLockFile && entry.path().filename() != kOutputLogFile)
      entries.push_back(entry.path());
  }
  if (ec) throw std::runtime_error(SystemErrorMessage(dir_, "cannot list the output folder", ec.value()));
  if (entries.empty()) return;
  const auto refuse = [&](const std::string& message) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw InvalidArgument(message);
  };
  if (!HoldsSemslamOutputs(dir_, had_lock_file)) {
    fs::remove(lock_path, ec);  // leave the user's folder as it was
    refuse(
        fmt::format("{}: --out is not empty and holds no semslam outputs ({} entries, e.g. {}); choose a new "
                    "or empty folder",
                    dir_.string(), entries.size(), entries.front().filename().string()));
  }
  if (const std::optional<fs::path> input = InputInside(dir_, options.inputs)) {
    refuse(fmt::format("{}: --out holds {}, which this {} reads; choose another folder for its outputs",
                       dir_.string(), input->string(), options.command));
  }
  if (!options.overwrite) {
    refuse(
        fmt::format("{}: --out holds an earlier run ({} entries); pass --overwrite to replace it, or choose "
                    "another folder",
                    dir_.string(), entries.size()));
  }
  for (const fs::path& entry : entries) {
    fs::remove_all(entry, ec);
    if (ec) {
      const std::string message =
          SystemErrorMessage(entry, "cannot remove the earlier run's output", ec.value());
      ::close(lock_fd_);
      lock_fd_ = -1;
      throw std::runtime_error(message);
    }
    ++removed_entries_;
  }
  spdlog::info("{}: --overwrite: removed the earlier run's {} entries", dir_.string(), removed_entries_);
}

RunOutputDir::~RunOutputDir() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the lock; the file stays and marks the folder
}

}  // namespace semslam
