#include "semslam/core/atomic_file.h"

#include <gtest/gtest.h>

#include <sched.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>

#include <fstream>
#include <sstream>
#include <string>

#include "support/test_support.h"

namespace semslam {
namespace {

std::string fmt_pid(const std::string& prefix, long pid, const std::string& suffix) {
  return prefix + std::to_string(pid) + suffix;
}

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


TEST(AtomicFile, ErrorsNameTheTargetAndTheSystemReason) {
  testing::TempDir dir;
  // A parent that is a regular file: "Not a directory" even for root (permissions do not stop root).
  WriteFileAtomically(dir / "file", "x");
  try {
    WriteFileAtomically(dir / "file" / "run.json", "{}");
    FAIL() << "writing below a regular file succeeded";
  } catch (const std::runtime_error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find((dir / "file").string()), std::string::npos) << message;
    EXPECT_NE(message.find("Not a directory"), std::string::npos) << message;
    EXPECT_EQ(message.find(".tmp"), std::string::npos) << "names the temporary file: " << message;
  }
}

// Writes 1 MiB into a 64 KiB tmpfs mounted in a mount namespace of a child process of its own (needs root or
// user namespaces; skipped otherwise): the error names the target and says "No space left on device".
TEST(AtomicFileDeathTest, FullDiskGivesNoSpaceLeft) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  testing::TempDir dir;
  const std::filesystem::path mount_point = dir / "small";
  std::filesystem::create_directories(mount_point);
  EXPECT_EXIT(
      {
        if (::unshare(CLONE_NEWNS) != 0 && ::unshare(CLONE_NEWUSER | CLONE_NEWNS) != 0) std::_Exit(77);
        if (::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) std::_Exit(77);
        if (::mount("tmpfs", mount_point.c_str(), "tmpfs", 0, "size=64k") != 0) std::_Exit(77);
        try {
          WriteFileAtomically(mount_point / "map.semslam", std::string(1 << 20, 'x'));
        } catch (const std::runtime_error& e) {
          const std::string message = e.what();
          const bool names_target = message.find((mount_point / "map.semslam").string()) != std::string::npos;
          const bool says_why = message.find("No space left on device") != std::string::npos;
          const bool no_temp_left = std::filesystem::is_empty(mount_point);
          std::fprintf(stderr, "%s\n", message.c_str());
          std::_Exit(names_target && says_why && no_temp_left ? 0 : 1);
        }
        std::_Exit(2);
      },
      [](int status) { return WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 77); },
      "");
}

TEST(AtomicFile, RecognizesItsTemporaryNames) {
  long pid = 0;
  EXPECT_TRUE(IsAtomicTempName(".run.json.tmp1234.0", &pid));
  EXPECT_EQ(pid, 1234);
  EXPECT_TRUE(IsAtomicTempName(".map.semslam.tmp7.15"));
  EXPECT_FALSE(IsAtomicTempName("run.json"));
  EXPECT_FALSE(IsAtomicTempName(".run.json.tmp.0"));
  EXPECT_FALSE(IsAtomicTempName(".run.json.tmp12x.0"));
  EXPECT_FALSE(IsAtomicTempName(".run.json.tmp12."));
  EXPECT_FALSE(IsAtomicTempName(".tmp12.0"));
  EXPECT_FALSE(IsAtomicTempName(".semslam.lock"));
}

TEST(AtomicFile, RemovesTemporaryFilesOfDeadWritersOnly) {
  testing::TempDir dir;
  // 999999999 is above any pid_max: no such process.
  const auto dead = dir / "plots" / ".gps.png.tmp999999999.3";
  const auto alive = dir / fmt_pid(".run.json.tmp", static_cast<long>(::getpid()), ".0");
  const auto other = dir / ".keep.tmp999999999";  // not our naming (no counter)
  std::filesystem::create_directories(dead.parent_path());
  for (const auto& p : {dead, alive, other}) std::ofstream(p) << "partial";
  EXPECT_EQ(RemoveStaleTempFiles(dir.path()), 1u);
  EXPECT_FALSE(std::filesystem::exists(dead));
  EXPECT_TRUE(std::filesystem::exists(alive));
  EXPECT_TRUE(std::filesystem::exists(other));
  EXPECT_EQ(RemoveStaleTempFiles(dir / "missing"), 0u);
}

}  // namespace
}  // namespace semslam
