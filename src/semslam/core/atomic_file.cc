#include "semslam/core/atomic_file.h"

#include <unistd.h>

#include <atomic>
#include <stdexcept>
#include <system_error>

#include <fmt/format.h>

namespace semslam {
namespace {

std::filesystem::path TempPathFor(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  return path.parent_path() /
         fmt::format(".{}.tmp{}.{}", path.filename().string(), static_cast<long>(::getpid()), counter++);
}

void EnsureParentExists(const std::filesystem::path& path) {
  const auto parent = path.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(parent, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot create directory: {}", parent.string(), ec.message()));
}

}  // namespace

void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents) {
  AtomicOutputFile file(path, std::ios::out | std::ios::binary);
  file.stream().write(contents.data(), static_cast<std::streamsize>(contents.size()));
  file.Commit();
}

AtomicOutputFile::AtomicOutputFile(std::filesystem::path path, std::ios::openmode mode)
    : path_(std::move(path)), temp_path_(TempPathFor(path_)) {
  EnsureParentExists(path_);
  stream_.open(temp_path_, mode | std::ios::out | std::ios::trunc);
  if (!stream_) throw std::runtime_error(fmt::format("{}: cannot open for writing", temp_path_.string()));
}

AtomicOutputFile::~AtomicOutputFile() {
  if (committed_) return;
  stream_.close();
  std::error_code ec;
  std::filesystem::remove(temp_path_, ec);
}

void AtomicOutputFile::Commit() {
  stream_.flush();
  if (!stream_) throw std::runtime_error(fmt::format("{}: write failed", temp_path_.string()));
  stream_.close();
  std::error_code ec;
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) {
    std::filesystem::remove(temp_path_, ec);
    throw std::runtime_error(fmt::format("{}: cannot move into place: {}", path_.string(), ec.message()));
  }
  committed_ = true;
}

}  // namespace semslam
