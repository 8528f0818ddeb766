#include "semslam/core/atomic_file.h"

#include <fcntl.h>
#include <fmt/format.h>
#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <streambuf>
#include <stdexcept>
#include <system_error>
#include <vector>

namespace semslam {
namespace {

constexpr std::string_view kTempTag = ".tmp";

std::filesystem::path TempPathFor(const std::filesystem::path& path) {
  static std::atomic<unsigned> counter{0};
  return path.parent_path() /
         fmt::format(".{}{}{}.{}", path.filename().string(), kTempTag, static_cast<long>(::getpid()), counter++);
}

void EnsureParentExists(const std::filesystem::path& path) {
  const auto parent = path.parent_path();
  if (parent.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(parent, ec);
  if (ec) throw std::runtime_error(SystemErrorMessage(parent, "cannot create directory", ec.value()));
}

bool AllDigits(std::string_view text) {
  if (text.empty()) return false;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

bool ProcessIsRunning(long pid) {
  if (pid <= 0) return false;
  return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}

}  // namespace

std::string SystemErrorMessage(const std::filesystem::path& path, std::string_view what, int error) {
  return fmt::format("{}: {}: {}", path.string(), what, std::strerror(error));
}

void WriteFileAtomically(const std::filesystem::path& path, std::string_view contents) {
  AtomicOutputFile file(path, std::ios::out | std::ios::binary);
  file.stream().write(contents.data(), static_cast<std::streamsize>(contents.size()));
  file.Commit();
}

// An output buffer on a file descriptor that remembers why writing failed: std::ofstream loses errno.
class AtomicOutputFile::Buffer : public std::streambuf {
 public:
  explicit Buffer(int fd) : fd_(fd) { setp(data_, data_ + sizeof(data_)); }
  ~Buffer() override { Close(); }

  int error() const { return error_; }
  // Writes what is buffered and closes the file; false (error() set) on failure.
  bool Close() {
    if (fd_ < 0) return error_ == 0;
    const bool flushed = Drain();
    if (::close(fd_) != 0 && error_ == 0) error_ = errno;
    fd_ = -1;
    return flushed && error_ == 0;
  }

 protected:
  int_type overflow(int_type c) override {
    if (!Drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    if (n <= epptr() - pptr()) {
      std::memcpy(pptr(), s, static_cast<size_t>(n));
      pbump(static_cast<int>(n));
      return n;
    }
    if (!Drain() || !WriteAll(s, static_cast<size_t>(n))) return 0;
    return n;
  }
  int sync() override { return Drain() ? 0 : -1; }
  // Seeking (a header filled in after its payload): what is buffered goes out first.
  pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode which) override {
    if (!(which & std::ios_base::out) || !Drain()) return pos_type(off_type(-1));
    const int whence = dir == std::ios_base::beg ? SEEK_SET : dir == std::ios_base::cur ? SEEK_CUR : SEEK_END;
    const off_t at = ::lseek(fd_, static_cast<off_t>(off), whence);
    if (at < 0) {
      if (error_ == 0) error_ = errno;
      return pos_type(off_type(-1));
    }
    return pos_type(static_cast<off_type>(at));
  }
  pos_type seekpos(pos_type pos, std::ios_base::openmode which) override {
    return seekoff(off_type(pos), std::ios_base::beg, which);
  }

 private:
  bool Drain() {
    const bool ok = WriteAll(pbase(), static_cast<size_t>(pptr() - pbase()));
    setp(data_, data_ + sizeof(data_));
    return ok;
  }
  bool WriteAll(const char* s, size_t n) {
    if (error_ != 0) return false;
    while (n > 0) {
      const ssize_t written = ::write(fd_, s, n);
      if (written < 0) {
        if (errno == EINTR) continue;
        error_ = errno;
        return false;
      }
      s += written;
      n -= static_cast<size_t>(written);
    }
    return true;
  }

  int fd_;
  int error_ = 0;
  char data_[1 << 16];
};

AtomicOutputFile::AtomicOutputFile(std::filesystem::path path, std::ios::openmode /*mode*/)
    : path_(std::move(path)), temp_path_(TempPathFor(path_)) {
  EnsureParentExists(path_);
  const int fd = ::open(temp_path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error(SystemErrorMessage(path_, "cannot create the file", errno));
  buffer_ = std::make_unique<Buffer>(fd);
  stream_ = std::make_unique<std::ostream>(buffer_.get());
}

AtomicOutputFile::~AtomicOutputFile() {
  if (committed_) return;
  buffer_->Close();
  std::error_code ec;
  std::filesystem::remove(temp_path_, ec);
}

void AtomicOutputFile::Commit() {
  stream_->flush();
  if (!buffer_->Close() || !*stream_) {
    const int error = buffer_->error() != 0 ? buffer_->error() : EIO;
    std::error_code ec;
    std::filesystem::remove(temp_path_, ec);
    throw std::runtime_error(SystemErrorMessage(path_, "cannot write", error));
  }
  std::error_code ec;
  std::filesystem::rename(temp_path_, path_, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(temp_path_, ignored);
    throw std::runtime_error(SystemErrorMessage(path_, "cannot move into place", ec.value()));
  }
  committed_ = true;
}

bool IsAtomicTempName(std::string_view name, long* pid) {
  // "." NAME ".tmp" PID "." N, NAME non-empty.
  if (name.size() < 1 + 1 + kTempTag.size() + 3 || name.front() != '.') return false;
  const size_t last_dot = name.rfind('.');
  if (last_dot == std::string_view::npos || !AllDigits(name.substr(last_dot + 1))) return false;
  const size_t tag = name.rfind(kTempTag, last_dot);
  if (tag == std::string_view::npos || tag < 2) return false;
  const std::string_view pid_text = name.substr(tag + kTempTag.size(), last_dot - tag - kTempTag.size());
  if (!AllDigits(pid_text)) return false;
  long value = 0;
  const auto [end, ec] = std::from_chars(pid_text.data(), pid_text.data() + pid_text.size(), value);
  if (ec != std::errc() || end != pid_text.data() + pid_text.size()) return false;
  if (pid != nullptr) *pid = value;
  return true;
}

size_t RemoveStaleTempFiles(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return 0;
  std::vector<std::filesystem::path> stale;
  for (auto it = std::filesystem::recursive_directory_iterator(
           dir, std::filesystem::directory_options::skip_permission_denied, ec);
       !ec && it != std::filesystem::recursive_directory_iterator(); it.increment(ec)) {
    long pid = 0;
    std::error_code type_error;
    if (!it->is_regular_file(type_error) || !IsAtomicTempName(it->path().filename().string(), &pid)) continue;
    if (!ProcessIsRunning(pid)) stale.push_back(it->path());
  }
  size_t removed = 0;
  for (const std::filesystem::path& path : stale) {
    std::error_code remove_error;
    if (std::filesystem::remove(path, remove_error)) ++removed;
  }
  return removed;
}

}  // namespace semslam
