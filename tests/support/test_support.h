#pragma once
// Helpers shared by all tests.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace semslam::testing {

// ../shared/data (research-only data, read in place, never copied into the repository).
std::filesystem::path SharedDataDir();
// The path of `relative` under SharedDataDir(), or an empty path if it does not exist.
std::filesystem::path SharedDataPath(const std::string& relative);
// The built `semslam` executable.
std::filesystem::path SemslamBinary();

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

}  // namespace semslam::testing

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
