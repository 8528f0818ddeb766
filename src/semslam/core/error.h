#pragma once
// Errors about input the user gave us: they name the file, the line and the field, so that a bad
// calibration or a truncated GPS log can be found and fixed without a debugger.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>

namespace semslam {

// Where in an input file something was read. line == 0 means "the file as a whole".
struct SourceLocation {
  std::filesystem::path file;
  int line = 0;

  std::string ToString() const;
};

// A problem with an input file or value; what() reads "FILE:LINE: field 'F': message".
class InputError : public std::runtime_error {
 public:
  InputError(const SourceLocation& where, std::string_view message);
  InputError(const SourceLocation& where, std::string_view field, std::string_view message);
  InputError(const std::filesystem::path& file, std::string_view message);

  const SourceLocation& where() const { return where_; }

 private:
  SourceLocation where_;
};

// A caller broke a function's contract (bad options, wrong sizes); a bug or a bad configuration.
class InvalidArgument : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Throws InvalidArgument with `message` unless `condition` holds. For Options::Check() and preconditions.
void Require(bool condition, std::string_view message);

}  // namespace semslam
