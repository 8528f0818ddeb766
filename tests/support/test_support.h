#pragma once
// Helpers shared by all tests.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

namespace semslam::testing {

// ../shared/data (research-only data, read in place, never copied into the repository).
std::filesystem::path SharedDataDir();
// The path of `relative` under SharedDataDir(), or an empty path if it does not exist.
std::filesystem::path SharedDataPath(const std::string& relative);
// The built `semslam` executable (SEMSLAM_BIN overrides it).
std::filesystem::path SemslamBinary();
// The `semslam` that renders the synthetic datasets tests run on: SEMSLAM_SYNTH_BIN, else SemslamBinary().
// Rendering is deterministic and not what a sanitizer build is there to check, so CI renders them once with
// the release binary and the sanitizer stages reuse them.
std::filesystem::path SynthBinary();

// A fresh, empty directory under the build tree, removed when the object goes out of scope.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Whether a missing shared-data folder must fail tests (CI sets SEMSLAM_REQUIRE_DATA=1) instead of skipping.
bool SharedDataRequired();

// How a run of the `semslam` binary ended, and what it printed.
struct CommandResult {
  int exit_code = -1;  // when the process exited
  int signal = 0;      // when a signal ended it (a crash)
  std::string out;     // stdout
  std::string err;     // stderr
  std::string command;

  bool Crashed() const { return signal != 0; }
  bool Succeeded() const { return signal == 0 && exit_code == 0; }
  // For failure messages: the command, how it ended and the end of its stderr.
  std::string Describe() const;
};

// Runs `semslam args...` (arguments passed as they are, no shell) with stdout and stderr captured through
// files in a temporary directory.
CommandResult RunSemslam(const std::vector<std::string>& args);
// The same with another `semslam` executable.
CommandResult RunBinary(const std::filesystem::path& binary, const std::vector<std::string>& args);

// The bytes of a file ("" if it cannot be read).
std::string ReadText(const std::filesystem::path& path);

}  // namespace semslam::testing

// Skips the test when the semslam binary has not been built.
#define SEMSLAM_REQUIRE_BINARY()                                                                  \
  if (!std::filesystem::exists(::semslam::testing::SemslamBinary())) {                            \
    GTEST_SKIP() << "semslam binary not built: " << ::semslam::testing::SemslamBinary().string(); \
  }

// Skips the test (or fails it when SEMSLAM_REQUIRE_DATA=1) if ../shared/data/<relative> is missing, and
// declares `var` as its path.
#define SEMSLAM_REQUIRE_SHARED_DATA(var, relative)                                                          \
  const std::filesystem::path var = ::semslam::testing::SharedDataPath(relative);                          \
  if (var.empty()) {                                                                                        \
    if (::semslam::testing::SharedDataRequired()) {                                                         \
      FAIL() << "shared data missing: " << (::semslam::testing::SharedDataDir() / (relative)).string();     \
    }                                                                                                       \
    GTEST_SKIP() << "shared data missing (tests that read real KITTI/Cityscapes data need ../shared/data): " \
                 << (::semslam::testing::SharedDataDir() / (relative)).string();                            \
  }
