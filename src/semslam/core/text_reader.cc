#include "semslam/core/text_reader.h"

#include <charconv>
#include <cmath>

#include <fmt/format.h>

namespace semslam {

std::vector<std::string_view> SplitTokens(std::string_view text, std::string_view delimiters) {
  std::vector<std::string_view> tokens;
  size_t pos = 0;
  while (pos < text.size()) {
    const size_t begin = text.find_first_not_of(delimiters, pos);
    if (begin == std::string_view::npos) break;
    size_t end = text.find_first_of(delimiters, begin);
    if (end == std::string_view::npos) end = text.size();
    tokens.push_back(text.substr(begin, end - begin));
    pos = end;
  }
  return tokens;
}

std::vector<std::string_view> SplitFields(std::string_view text, char delimiter) {
  std::vector<std::string_view> fields;
  size_t begin = 0;
  while (true) {
    const size_t end = text.find(delimiter, begin);
    if (end == std::string_view::npos) {
      fields.push_back(text.substr(begin));
      return fields;
    }
    fields.push_back(text.substr(begin, end - begin));
    begin = end + 1;
  }
}

std::string_view Trim(std::string_view text) {
  const size_t begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string_view::npos) return {};
  const size_t end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

namespace {

double ParseDoubleImpl(std::string_view token, const SourceLocation& where, std::string_view field) {
  token = Trim(token);
  if (token.empty()) throw InputError(where, field, "empty value where a number was expected");
  if (token.front() == '+') token.remove_prefix(1);
  double value = 0.0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (ec == std::errc::result_out_of_range) {
    throw InputError(where, field, fmt::format("number '{}' is out of range", token));
  }
  if (ec != std::errc() || end != token.data() + token.size()) {
    throw InputError(where, field, fmt::format("'{}' is not a number", token));
  }
  return value;
}

}  // namespace

double ParseDouble(std::string_view token, const SourceLocation& where, std::string_view field) {
  const double value = ParseDoubleImpl(token, where, field);
  if (!std::isfinite(value)) throw InputError(where, field, fmt::format("'{}' is not finite", Trim(token)));
  return value;
}

double ParseDoubleAllowNonFinite(std::string_view token, const SourceLocation& where, std::string_view field) {
  return ParseDoubleImpl(token, where, field);
}

long long ParseInt(std::string_view token, const SourceLocation& where, std::string_view field) {
  token = Trim(token);
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  long long value = 0;
  const auto [end, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
  if (token.empty() || ec != std::errc() || end != token.data() + token.size()) {
    throw InputError(where, field, fmt::format("'{}' is not an integer", token));
  }
  return value;
}

TextReader::TextReader(std::filesystem::path file) : file_(std::move(file)), stream_(file_) {
  if (!std::filesystem::exists(file_)) throw InputError(file_, "file not found");
  if (!stream_) throw InputError(file_, "cannot open file for reading");
}

std::optional<std::string> TextReader::NextLine() {
  std::string line;
  if (!std::getline(stream_, line)) {
    if (stream_.bad()) throw InputError(Where(), "read error");
    return std::nullopt;
  }
  ++line_number_;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return line;
}

}  // namespace semslam
