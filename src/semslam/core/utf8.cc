#include "semslam/core/utf8.h"

#include <fmt/format.h>

namespace semslam {

size_t FindInvalidUtf8(std::string_view text) {
  const auto byte = [&](size_t i) { return static_cast<unsigned char>(text[i]); };
  size_t i = 0;
  while (i < text.size()) {
    const unsigned char c = byte(i);
    if (c < 0x80) {
      ++i;
      continue;
    }
    size_t length = 0;
    unsigned char lo = 0x80, hi = 0xBF;  // the allowed range of the second byte (RFC 3629, table 3-7)
    if (c >= 0xC2 && c <= 0xDF) {
      length = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      length = 3;
      if (c == 0xE0) lo = 0xA0;  // no overlong forms
      if (c == 0xED) hi = 0x9F;  // no surrogates
    } else if (c >= 0xF0 && c <= 0xF4) {
      length = 4;
      if (c == 0xF0) lo = 0x90;  // no overlong forms
      if (c == 0xF4) hi = 0x8F;  // nothing above U+10FFFF
    } else {
      return i;
    }
    if (i + length > text.size()) return i;
    if (byte(i + 1) < lo || byte(i + 1) > hi) return i;
    for (size_t k = 2; k < length; ++k) {
      if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return i;
    }
    i += length;
  }
  return std::string_view::npos;
}

namespace {

std::string ShowBadByte(std::string_view text, size_t offset) {
  return fmt::format("byte 0x{:02X} at offset {} is not UTF-8 (a Latin-1 or Windows-1252 file? convert it, "
                     "e.g. with iconv -f latin1 -t utf-8)",
                     static_cast<unsigned char>(text[offset]), offset);
}

}  // namespace

void RequireUtf8(std::string_view text, const SourceLocation& where, std::string_view field) {
  const size_t bad = FindInvalidUtf8(text);
  if (bad != std::string_view::npos) throw InputError(where, field, ShowBadByte(text, bad));
}

void RequireUtf8Path(const std::filesystem::path& path, std::string_view what) {
  const std::string& text = path.native();
  const size_t bad = FindInvalidUtf8(text);
  if (bad == std::string_view::npos) return;
  throw InvalidArgument(fmt::format(
      "{} '{}': the path is not UTF-8 (byte 0x{:02X} at offset {}); semslam records paths in run.json and "
      "the report, which must be UTF-8: rename it or use a link with a UTF-8 name",
      what, std::string(text.substr(0, bad)) + "?", static_cast<unsigned char>(text[bad]), bad));
}

}  // namespace semslam
