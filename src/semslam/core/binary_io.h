#pragma once
// Little-endian binary encoding for semslam's own file formats (maps, vocabularies), with a 64-bit
// FNV-1a checksum so corrupt or truncated files are detected.

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "semslam/core/error.h"

namespace semslam {

std::uint64_t Fnv1a64(std::string_view bytes);

class BinaryWriter {
 public:
  template <typename T>
  void Put(const T& value) {
    static_assert(std::is_trivially_copyable_v<T>);
    buffer_.append(reinterpret_cast<const char*>(&value), sizeof(T));
  }
  template <typename T>
  void PutVector(const std::vector<T>& values) {
    static_assert(std::is_trivially_copyable_v<T>);
    Put<std::uint64_t>(values.size());
    buffer_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  }
  void PutString(std::string_view s) {
    Put<std::uint64_t>(s.size());
    buffer_.append(s);
  }
  const std::string& bytes() const { return buffer_; }
  std::string& bytes() { return buffer_; }

 private:
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
struct ChecksummedFile {
  std::uint32_t version = 0;
  std::string payload;
};
// Verifies magic, size and checksum; throws InputError naming the file otherwise.
ChecksummedFile ReadChecksummedFile(const std::filesystem::path& path, std::string_view magic8);

}  // namespace semslam
