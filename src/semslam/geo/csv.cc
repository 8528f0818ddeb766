#include "semslam/geo/csv.h"

#include <cctype>

#include "semslam/core/text_reader.h"

namespace semslam {

std::vector<std::string> SplitCsvRecord(std::string_view line, const SourceLocation& where) {
  std::vector<std::string> fields;
  size_t pos = 0;
  const size_t n = line.size();
  while (true) {
    // Skip blanks before a field.
    size_t begin = pos;
    while (begin < n && (line[begin] == ' ' || line[begin] == '\t')) ++begin;
    if (begin < n && line[begin] == '"') {
      std::string field;
      size_t i = begin + 1;
      bool closed = false;
      while (i < n) {
        if (line[i] == '"') {
          if (i + 1 < n && line[i + 1] == '"') {
            field.push_back('"');
            i += 2;
            continue;
          }
          closed = true;
          ++i;
          break;
        }
        field.push_back(line[i++]);
      }
      if (!closed) {
        throw InputError(where, "field " + std::to_string(fields.size() + 1), "unterminated quoted field");
      }
      while (i < n && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
      if (i < n && line[i] != ',') {
        throw InputError(where, "field " + std::to_string(fields.size() + 1), "text after a closing quote");
      }
      fields.push_back(std::move(field));
      if (i >= n) return fields;
      pos = i + 1;
    } else {
      size_t end = line.find(',', begin);
      if (end == std::string_view::npos) end = n;
      fields.emplace_back(Trim(line.substr(begin, end - begin)));
      if (end >= n) return fields;
      pos = end + 1;
    }
  }
}

std::string NormalizeColumnName(std::string_view name) {
  std::string out;
  for (const char c : Trim(name)) {
    if (c == ' ' || c == '_' || c == '-' || c == '\t') continue;
    out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  }
  return out;
}

}  // namespace semslam
