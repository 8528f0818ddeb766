// ReadImage, ReadGreyImage, GreyFromColor and WritePng (declared in sequence.h).

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <system_error>
#include <vector>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/io/sequence.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

std::uint32_t Crc32(const unsigned char* data, size_t size, std::uint32_t crc = 0xFFFFFFFFu) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t n = 0; n < 256; ++n) {
      std::uint32_t c = n;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[n] = c;
    }
    return t;
  }();
  for (size_t i = 0; i < size; ++i) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return crc;
}

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

// Walks a PNG's chunks and checks their CRCs, so that a truncated or damaged file is reported here, in one
// line naming it, instead of by the decoder (libpng writes its own complaints to stderr). Returns an empty
// string for a sound file, else what is wrong.
std::string CheckPngStructure(const std::vector<unsigned char>& bytes) {
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() < 8 || !std::equal(kSignature, kSignature + 8, bytes.begin())) return "not a PNG file";
  size_t offset = 8;
  while (offset + 12 <= bytes.size()) {
    const std::uint32_t length = BigEndian32(&bytes[offset]);
    if (length > bytes.size() - offset - 12) return fmt::format("truncated (chunk at byte {})", offset);
    const unsigned char* type = &bytes[offset + 4];
    const std::uint32_t crc = Crc32(type, 4 + size_t{length}) ^ 0xFFFFFFFFu;
    if (crc != BigEndian32(&bytes[offset + 8 + length]))
      return fmt::format("damaged (CRC of the chunk at byte {})", offset);
    if (std::equal(type, type + 4, "IEND")) return {};
    offset += 12 + size_t{length};
  }
  return "truncated (no IEND chunk)";
}

}  // namespace

cv::Mat ReadImageUnchanged(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw InputError(path, "image file not found");
  std::ifstream in(path, std::ios::binary);
  const std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) throw InputError(path, "cannot read the image file");
  if (bytes.size() >= 8 && bytes[0] == 0x89 && bytes[1] == 'P') {
    if (const std::string problem = CheckPngStructure(bytes); !problem.empty()) {
      throw InputError(path, "corrupt PNG: " + problem);
    }
  }
  if (bytes.empty()) throw InputError(path, "the image file is empty");
  cv::Mat image;
  try {
    image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    image.release();
  }
  if (image.empty()) throw InputError(path, "cannot decode the image (corrupt or not an image)");
  return image;
}

cv::Mat ReadImage(const fs::path& path) {
  cv::Mat image = ReadImageUnchanged(path);
  if (image.depth() == CV_16U) {
    image.convertTo(image, CV_8U, 1.0 / 257.0);
  } else if (image.depth() != CV_8U) {
    throw InputError(
        path, fmt::format("unsupported pixel depth (OpenCV depth {}); expected 8 or 16 bit", image.depth()));
  }
  if (image.channels() == 4) {
    cv::cvtColor(image, image, cv::COLOR_BGRA2BGR);
  } else if (image.channels() != 1 && image.channels() != 3) {
    throw InputError(path, fmt::format("unsupported number of channels ({})", image.channels()));
  }
  return image;
}

cv::Mat GreyFromColor(const cv::Mat& image) {
  Require(image.type() == CV_8UC1 || image.type() == CV_8UC3,
          "GreyFromColor: expected an 8-bit grey or BGR image");
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}

cv::Mat ReadGreyImage(const fs::path& path) { return GreyFromColor(ReadImage(path)); }

void WritePng(const fs::path& path, const cv::Mat& image, int compression) {
  Require(!image.empty(), "WritePng: empty image");
  Require(compression >= 0 && compression <= 9, "WritePng: compression must be in 0..9");
  Require(image.depth() == CV_8U || image.depth() == CV_16U, "WritePng: PNG holds 8- or 16-bit images only");
  std::vector<uchar> bytes;
  if (!cv::imencode(".png", image, bytes, {cv::IMWRITE_PNG_COMPRESSION, compression})) {
    throw std::runtime_error(fmt::format("{}: PNG encoding failed", path.string()));
  }
  WriteFileAtomically(path, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

}  // namespace semslam
