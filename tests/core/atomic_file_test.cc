#include "semslam/core/atomic_file.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "support/test_support.h"

namespace semslam {
namespace {

std::string ReadAll(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(AtomicFile, WritesAndReplaces) {
  testing::TempDir dir;
  const auto path = dir / "nested/out.txt";
  WriteFileAtomically(path, "first");
  EXPECT_EQ(ReadAll(path), "first");
  WriteFileAtomically(path, "second");
  EXPECT_EQ(ReadAll(path), "second");
  // Only the target remains: no temporary files left behind.
  int count = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(path.parent_path())) ++count;
  EXPECT_EQ(count, 1);
}

TEST(AtomicFile, UncommittedLeavesOldContents) {
  testing::TempDir dir;
  const auto path = dir / "out.txt";
  WriteFileAtomically(path, "kept");
  {
    AtomicOutputFile file(path);
    file.stream() << "half-written";
    // Destroyed without Commit(): as if the process died mid-write.
  }
  EXPECT_EQ(ReadAll(path), "kept");
  int count = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(dir.path())) ++count;
  EXPECT_EQ(count, 1);
}

}  // namespace
}  // namespace semslam
