#pragma once
// Every file semslam writes goes through here: written to a temporary file beside the target and
// renamed over it, so a crash never leaves a half-written output behind.

#include <filesystem>
#include <fstream>
#include <string_view>

namespace semslam {

// Writes `contents` to `path` atomically. Creates missing parent directories. Throws std::runtime_error.
void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents);

// A stream to a temporary file that replaces `path` on Commit(); dropped without Commit(), it leaves
// `path` untouched and removes the temporary file.
class AtomicOutputFile {
 public:
  explicit AtomicOutputFile(std::filesystem::path path, std::ios::openmode mode = std::ios::out);
  ~AtomicOutputFile();
  AtomicOutputFile(const AtomicOutputFile&) = delete;
  AtomicOutputFile& operator=(const AtomicOutputFile&) = delete;

  std::ofstream& stream() { return stream_; }
  // Flushes, checks for write errors, and renames into place. Throws std::runtime_error on failure.
  void Commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  std::ofstream stream_;
  bool committed_ = false;
};

}  // namespace semslam
