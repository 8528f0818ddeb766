#pragma once
// Little-endian binary encoding for semslam's own file formats (maps, vocabularies), with a 64-bit
// FNV-1a checksum so corrupt or truncated files are detected.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "semslam/core/error.h"

namespace semslam {

constexpr std::uint64_t kFnv1a64Basis = 14695981039346656037ull;
// FNV-1a over `bytes`, continuing from `hash` (a checksum computed piece by piece).
std::uint64_t Fnv1a64(std::string_view bytes, std::uint64_t hash = kFnv1a64Basis);

class BinaryWriter {
 public:
  BinaryWriter() = default;
  // Streaming: whenever a chunk (1 MiB) is buffered, it is passed to `sink` and the buffer emptied; Flush()
  // passes the rest. A large file is then never whole in memory.
  explicit BinaryWriter(std::function<void(std::string_view)> sink) : sink_(std::move(sink)) {}

  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    buffer_.append(reinterpret_cast<const char*>(&value), sizeof(T));
    FlushFull();
  }
  template <typename T>
  void PutVector(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>);
    Put<std::uint64_t>(values.size());
    buffer_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
    FlushFull();
  }
  void PutString(std::string_view s) {
    Put<std::uint64_t>(s.size());
    buffer_.append(s);
    FlushFull();
  }
  void Flush();
  // What is buffered: everything written, without a sink.
  const std::string& bytes() const { return buffer_; }
  std::string& bytes() { return buffer_; }

 private:
  static constexpr size_t kChunk = size_t{1} << 20;
  void FlushFull() {
    if (sink_ && buffer_.size() >= kChunk) Flush();
  }
  std::function<void(std::string_view)> sink_;
  std::string buffer_;
};

// Reads what BinaryWriter wrote; any read past the end throws InputError naming the file and `context`.
class BinaryReader {
 public:
  BinaryReader(std::string_view bytes, std::filesystem::path file) : bytes_(bytes), file_(std::move(file)) {}

  void set_context(std::string context) { context_ = std::move(context); }
  template <typename T>
  T Get() {
    static_assert(std::is_trivially_copyable_v<T>);
    Need(sizeof(T));
    T value;
    std::memcpy(&value, bytes_.data() + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  template <typename T>
  std::vector<T> GetVector(std::uint64_t max_count = UINT64_MAX) {
    const auto n = Get<std::uint64_t>();
    if (n > max_count || n > (bytes_.size() - offset_) / std::max<size_t>(sizeof(T), 1)) Fail("bad element count");
    std::vector<T> values(n);
    if (n > 0) std::memcpy(values.data(), bytes_.data() + offset_, n * sizeof(T));  // data() is null when empty
    offset_ += n * sizeof(T);
    return values;
  }
  std::string GetString() {
    const auto n = Get<std::uint64_t>();
    Need(n);
    std::string s(bytes_.substr(offset_, n));
    offset_ += n;
    return s;
  }
  bool AtEnd() const { return offset_ == bytes_.size(); }
  size_t offset() const { return offset_; }
  const std::filesystem::path& file() const { return file_; }
  [[noreturn]] void Fail(std::string_view message) const;

 private:
  void Need(size_t n) const {
    if (n > bytes_.size() - offset_) Fail("unexpected end of data (file truncated?)");
  }
  std::string_view bytes_;
  size_t offset_ = 0;
  std::filesystem::path file_;
  std::string context_;
};

// A file = magic (8 bytes) + u32 version + u64 payload size + u64 FNV-1a of the payload + payload.
// Written atomically.
void WriteChecksummedFile(const std::filesystem::path& path, std::string_view magic8, std::uint32_t version,
                          std::string_view payload);

class AtomicOutputFile;

// The same file, written as its payload is produced: a chunk at a time, so that saving a map of a few hundred
// MB does not hold a second copy of it in memory. Size and checksum go into the header at Commit(); dropped
// without Commit(), nothing is written. Errors as AtomicOutputFile's.
class ChecksummedFileWriter {
 public:
  ChecksummedFileWriter(const std::filesystem::path& path, std::string_view magic8, std::uint32_t version);
  ~ChecksummedFileWriter();
  ChecksummedFileWriter(const ChecksummedFileWriter&) = delete;
  ChecksummedFileWriter& operator=(const ChecksummedFileWriter&) = delete;

  BinaryWriter& payload() { return payload_; }
  void Commit();

 private:
  void Append(std::string_view bytes);

  std::unique_ptr<AtomicOutputFile> file_;
  std::uint64_t size_ = 0;
  std::uint64_t checksum_ = kFnv1a64Basis;
  BinaryWriter payload_;
};
struct ChecksummedFile {
  std::uint32_t version = 0;
  std::string payload;
};
// Verifies magic, size and checksum; throws InputError naming the file otherwise.
ChecksummedFile ReadChecksummedFile(const std::filesystem::path& path, std::string_view magic8);

}  // namespace semslam
