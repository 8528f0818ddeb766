#pragma once
// Every file semslam writes goes through here: written to a temporary file beside the target and
// renamed over it, so a crash never leaves a half-written output behind.

#include <cstddef>
#include <filesystem>
#include <fstream>  // callers rely on it
#include <ios>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>

namespace semslam {

// Writes `contents` to `path` atomically. Creates missing parent directories. Throws std::runtime_error naming
// `path` and the system's reason ("No space left on device", "Permission denied").
void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents);

// A stream to a temporary file that replaces `path` on Commit(); dropped without Commit(), it leaves
// `path` untouched and removes the temporary file. Bytes are written as they are (no text-mode translation).
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::filesystem::path path, std::ios::openmode mode = std::ios::out);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ostream& stream() { return *stream_; }
  // Flushes, checks for write errors, and renames into place. Throws std::runtime_error naming `path` and
  // the system's reason on failure.
  void Commit();

 private:
  class Buffer;  // writes through write(2) and keeps the errno of the first failure (a full disk)
  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  std::unique_ptr<Buffer> buffer_;
  std::unique_ptr<std::ostream> stream_;
  bool committed_ = false;
};

// Whether `name` is a temporary file name of AtomicOutputFile (".NAME.tmpPID.N"); sets *pid when it is.
bool IsAtomicTempName(std::string_view name, long* pid = nullptr);

// Removes, under `dir` (recursively), the temporary files that a semslam process which is no longer running
// left behind (it was killed while writing). Files of running processes are kept. Returns how many were
// removed; errors are ignored (the files are harmless).
size_t RemoveStaleTempFiles(const std::filesystem::path& dir);

// "PATH: WHAT: REASON" with REASON the text of errno `error` (strerror), e.g.
// "out/run.json: cannot write: No space left on device".
std::string SystemErrorMessage(const std::filesystem::path& path, std::string_view what, int error);

}  // namespace semslam
