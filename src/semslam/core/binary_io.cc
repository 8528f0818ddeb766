#include "semslam/core/binary_io.h"

#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "semslam/core/atomic_file.h"

namespace semslam {

std::uint64_t Fnv1a64(std::string_view bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

void BinaryReader::Fail(std::string_view message) const {
  throw InputError(file_, fmt::format("{}{}at byte {}: {}", context_, context_.empty() ? "" : ", ", offset_, message));
}

void WriteChecksummedFile(const std::filesystem::path& path, std::string_view magic8, std::uint32_t version,
                          std::string_view payload) {
  Require(magic8.size() == 8, "file magic must be 8 bytes");
  BinaryWriter header;
  header.bytes().append(magic8);
  header.Put<std::uint32_t>(version);
  header.Put<std::uint64_t>(payload.size());
  header.Put<std::uint64_t>(Fnv1a64(payload));
  AtomicOutputFile file(path, std::ios::out | std::ios::binary);
  file.stream().write(header.bytes().data(), static_cast<std::streamsize>(header.bytes().size()));
  file.stream().write(payload.data(), static_cast<std::streamsize>(payload.size()));
  file.Commit();
}

ChecksummedFile ReadChecksummedFile(const std::filesystem::path& path, std::string_view magic8) {
  if (!std::filesystem::exists(path)) throw InputError(path, "file not found");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file for reading");
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string bytes = ss.str();
  constexpr size_t kHeader = 8 + 4 + 8 + 8;
  if (bytes.size() < kHeader || std::string_view(bytes).substr(0, 8) != magic8) {
    throw InputError(path, fmt::format("not a {} file (wrong magic bytes)", magic8.substr(0, magic8.find('\0'))));
  }
  BinaryReader reader(std::string_view(bytes).substr(8), path);
  ChecksummedFile file;
  file.version = reader.Get<std::uint32_t>();
  const auto size = reader.Get<std::uint64_t>();
  const auto checksum = reader.Get<std::uint64_t>();
  if (size != bytes.size() - kHeader) {
    throw InputError(path, fmt::format("payload is {} bytes, header says {} (truncated file?)", bytes.size() - kHeader, size));
  }
  file.payload = bytes.substr(kHeader);
  if (Fnv1a64(file.payload) != checksum) throw InputError(path, "checksum mismatch: the file is corrupt");
  return file;
}

}  // namespace semslam
