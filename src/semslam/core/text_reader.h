#pragma once
// Line-oriented reading of text input files with located, typed field parsing.

#include <Eigen/Core>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/core/error.h"

namespace semslam {

// Splits on any run of the given delimiter characters; empty tokens are dropped.
std::vector<std::string_view> SplitTokens(std::string_view text, std::string_view delimiters = " \t\r");
// Splits on every occurrence of `delimiter` (CSV style); empty fields are kept.
std::vector<std::string_view> SplitFields(std::string_view text, char delimiter);
std::string_view Trim(std::string_view text);

// Parses a whole token as a finite number; throws InputError naming `where` and `field` otherwise.
double ParseDouble(std::string_view token, const SourceLocation& where, std::string_view field);
// Like ParseDouble but NaN and infinities are accepted (for formats that use them as "no value").
double ParseDoubleAllowNonFinite(std::string_view token, const SourceLocation& where, std::string_view field);
long long ParseInt(std::string_view token, const SourceLocation& where, std::string_view field);

// Reads a text file line by line and keeps the location for error messages.
class TextReader {
 public:
  // Throws InputError if the file cannot be opened.
  explicit TextReader(std::filesystem::path file);

  // Next line (without the newline); std::nullopt at the end of the file.
  std::optional<std::string> NextLine();
  // Location of the line NextLine() returned last.
  SourceLocation Where() const { return {file_, line_number_}; }
  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  std::ifstream stream_;
  int line_number_ = 0;
};

// Parses `tokens` (all of them) as exactly N numbers, naming fields `field_prefix[i]` in errors.
template <int N>
Eigen::Matrix<double, N, 1> ParseVector(const std::vector<std::string_view>& tokens, const SourceLocation& where,
                                        std::string_view field_prefix) {
  if (static_cast<int>(tokens.size()) != N) {
    throw InputError(where, field_prefix,
                     "expected " + std::to_string(N) + " numbers, found " + std::to_string(tokens.size()));
  }
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) {
    v[i] = ParseDouble(tokens[i], where, std::string(field_prefix) + "[" + std::to_string(i) + "]");
  }
  return v;
}

}  // namespace semslam
