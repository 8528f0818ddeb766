#pragma once
// CSV records (RFC 4180 on one line): fields separated by commas, optionally in double quotes, a doubled
// quote inside quotes standing for one quote. Used by the GPS and landmark catalogue readers.

#include <string>
#include <string_view>
#include <vector>

#include "semslam/core/error.h"

namespace semslam {

// Splits one line into fields; unquoted fields are trimmed of surrounding blanks, quoted ones kept verbatim.
// Throws InputError at `where` on an unterminated quote or text after a closing quote.
std::vector<std::string> SplitCsvRecord(std::string_view line, const SourceLocation& where);

// Lower case with spaces, '-' and '_' removed: "Lat_Deg" -> "latdeg". For matching header names.
std::string NormalizeColumnName(std::string_view name);

}  // namespace semslam
