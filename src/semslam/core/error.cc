#include "semslam/core/error.h"

#include <fmt/format.h>

namespace semslam {

std::string SourceLocation::ToString() const {
  if (line > 0) return fmt::format("{}:{}", file.string(), line);
  return file.string();
}

InputError::InputError(const SourceLocation& where, std::string_view message)
    : std::runtime_error(fmt::format("{}: {}", where.ToString(), message)), where_(where) {}

InputError::InputError(const SourceLocation& where, std::string_view field, std::string_view message)
    : std::runtime_error(fmt::format("{}: field '{}': {}", where.ToString(), field, message)),
      where_(where) {}

InputError::InputError(const std::filesystem::path& file, std::string_view message)
    : InputError(SourceLocation{file, 0}, message) {}

void Require(bool condition, std::string_view message) {
  if (!condition) throw InvalidArgument(std::string(message));
}

}  // namespace semslam
