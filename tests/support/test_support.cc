#include "support/test_support.h"

#include <atomic>
#include <cstdlib>
#include <random>
#include <string_view>

#include <fmt/format.h>

namespace semslam::testing {

std::filesystem::path SharedDataDir() {
  if (const char* env = std::getenv("SEMSLAM_SHARED_DATA"); env != nullptr && *env != '\0') return env;
  return SEMSLAM_SHARED_DATA_DIR;
}

std::filesystem::path SharedDataPath(const std::string& relative) {
  const auto path = SharedDataDir() / relative;
  return std::filesystem::exists(path) ? path : std::filesystem::path{};
}

std::filesystem::path SemslamBinary() {
  if (const char* env = std::getenv("SEMSLAM_BIN"); env != nullptr && *env != '\0') return env;
  return std::filesystem::path(SEMSLAM_BINARY_DIR) / "bin" / "semslam";
}

bool SharedDataRequired() {
  const char* env = std::getenv("SEMSLAM_REQUIRE_DATA");
  return env != nullptr && std::string_view(env) == "1";
}

TempDir::TempDir() {
  static std::atomic<int> counter{0};
  std::random_device rd;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string test_name = info ? fmt::format("{}.{}", info->test_suite_name(), info->name()) : "test";
  path_ = std::filesystem::path(SEMSLAM_BINARY_DIR) / "test_tmp" /
          fmt::format("{}-{}-{}", test_name, rd() % 100000, counter++);
  std::filesystem::remove_all(path_);
  std::filesystem::create_directories(path_);
}

TempDir::~TempDir() {
  if (std::getenv("SEMSLAM_KEEP_TEST_TMP") != nullptr) return;
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
}

}  // namespace semslam::testing
