#include "semslam/core/binary_io.h"

#include <fstream>

#include <fmt/format.h>

#include "semslam/core/atomic_file.h"

namespace semslam {

std::uint64_t Fnv1a64(std::string_view bytes, std::uint64_t hash) {
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

void BinaryWriter::Flush() {
  if (!sink_ || buffer_.empty()) return;
  sink_(buffer_);
  buffer_.clear();
}

void BinaryReader::Fail(std::string_view message) const {
  throw InputError(file_, fmt::format("{}{}at byte {}: {}", context_, context_.empty() ? "" : ", ", offset_, message));
}

namespace {

constexpr size_t kHeaderSize = 8 + 4 + 8 + 8;
constexpr std::streamoff kSizeOffset = 8 + 4;  // then the checksum

std::string Header(std::string_view magic8, std::uint32_t version, std::uint64_t size, std::uint64_t checksum) {
  Require(magic8.size() == 8, "file magic must be 8 bytes");
  BinaryWriter header;
  header.bytes().append(magic8);
  header.Put<std::uint32_t>(version);
  header.Put<std::uint64_t>(size);
  header.Put<std::uint64_t>(checksum);
  return header.bytes();
}

}  // namespace

void WriteChecksummedFile(const std::filesystem::path& path, std::string_view magic8, std::uint32_t version,
                          std::string_view payload) {
  // Written whole, not through ChecksummedFileWriter, so that a test can hold either writer against the other.
  const std::string header = Header(magic8, version, payload.size(), Fnv1a64(payload));
  AtomicOutputFile file(path, std::ios::out | std::ios::binary);
  file.stream().write(header.data(), static_cast<std::streamsize>(header.size()));
  file.stream().write(payload.data(), static_cast<std::streamsize>(payload.size()));
  file.Commit();
}

ChecksummedFileWriter::ChecksummedFileWriter(const std::filesystem::path& path, std::string_view magic8,
                                             std::uint32_t version)
    : payload_([this](std::string_view bytes) { Append(bytes); }) {
  const std::string header = Header(magic8, version, 0, 0);  // size and checksum filled in at Commit()
  file_ = std::make_unique<AtomicOutputFile>(path, std::ios::out | std::ios::binary);
  file_->stream().write(header.data(), static_cast<std::streamsize>(header.size()));
}

ChecksummedFileWriter::~ChecksummedFileWriter() = default;

void ChecksummedFileWriter::Append(std::string_view bytes) {
  size_ += bytes.size();
  checksum_ = Fnv1a64(bytes, checksum_);
  file_->stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void ChecksummedFileWriter::Commit() {
  payload_.Flush();
  BinaryWriter fields;
  fields.Put<std::uint64_t>(size_);
  fields.Put<std::uint64_t>(checksum_);
  std::ostream& out = file_->stream();
  out.seekp(kSizeOffset);
  out.write(fields.bytes().data(), static_cast<std::streamsize>(fields.bytes().size()));
  file_->Commit();  // reports a failed seek or write with the system's reason
}

ChecksummedFile ReadChecksummedFile(const std::filesystem::path& path, std::string_view magic8) {
  if (!std::filesystem::exists(path)) throw InputError(path, "file not found");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open file for reading");
  // Read into one buffer, which then becomes the payload in place: a large map is held once, not thrice.
  std::error_code error;
  const std::uintmax_t file_size = std::filesystem::file_size(path, error);
  if (error) throw InputError(path, fmt::format("cannot read the file: {}", error.message()));
  std::string bytes(static_cast<size_t>(file_size), '\0');
  in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (in.gcount() != static_cast<std::streamsize>(bytes.size())) throw InputError(path, "cannot read the file");
  if (bytes.empty()) throw InputError(path, "the file is empty (0 bytes)");
  if (bytes.size() < kHeaderSize || std::string_view(bytes).substr(0, 8) != magic8) {
    throw InputError(path, fmt::format("not a {} file (wrong magic bytes)", magic8.substr(0, magic8.find('\0'))));
  }
  BinaryReader reader(std::string_view(bytes).substr(8, kHeaderSize - 8), path);
  ChecksummedFile file;
  file.version = reader.Get<std::uint32_t>();
  const auto size = reader.Get<std::uint64_t>();
  const auto checksum = reader.Get<std::uint64_t>();
  if (size != bytes.size() - kHeaderSize) {
    throw InputError(path, fmt::format("payload is {} bytes, header says {} (truncated file?)",
                                       bytes.size() - kHeaderSize, size));
  }
  bytes.erase(0, kHeaderSize);
  file.payload = std::move(bytes);
  if (Fnv1a64(file.payload) != checksum) throw InputError(path, "checksum mismatch: the file is corrupt");
  return file;
}

}  // namespace semslam
