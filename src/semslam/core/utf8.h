#pragma once
// Text semslam writes into JSON, GeoJSON and HTML must be UTF-8. Input that is not (a Latin-1 landmark name,
// a folder name with a Latin-1 byte) is refused when it is read, naming where it came from, instead of
// failing when the outputs are written at the end of a run.

#include <cstddef>
#include <filesystem>
#include <string_view>

#include "semslam/core/error.h"

namespace semslam {

// The offset of the first byte that is not part of well-formed UTF-8 (overlong forms, surrogates and code
// points above U+10FFFF are ill-formed), or std::string_view::npos when the whole text is UTF-8.
size_t FindInvalidUtf8(std::string_view text);
inline bool IsValidUtf8(std::string_view text) { return FindInvalidUtf8(text) == std::string_view::npos; }

// Throws InputError at `where`, naming `field`, when `text` is not UTF-8.
void RequireUtf8(std::string_view text, const SourceLocation& where, std::string_view field);

// Throws InvalidArgument naming `what` (e.g. "--sequence") when the path is not UTF-8: semslam records its
// paths in run.json and the report.
void RequireUtf8Path(const std::filesystem::path& path, std::string_view what);

}  // namespace semslam
