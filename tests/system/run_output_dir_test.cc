// The output folder policy (system/run_output_dir.h): writable and free before the first frame, one writer at a
// time, nothing of an earlier run kept, and never a user's own folder emptied.

#include "semslam/system/run_output_dir.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <fstream>
#include <string>

#include "semslam/core/error.h"
#include "support/test_support.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;

std::string ErrorOf(const fs::path& dir, const OutputDirOptions& options = {}) {
  try {
    RunOutputDir out(dir, options);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(RunOutputDir, CreatesAMissingFolderAndMarksIt) {
  testing::TempDir tmp;
  { RunOutputDir out(tmp / "a" / "b"); }
  EXPECT_TRUE(fs::is_directory(tmp / "a" / "b"));
  EXPECT_TRUE(fs::exists(tmp / "a" / "b" / kOutputLockFile));
  // Nothing but the mark: the next run needs no --overwrite.
  EXPECT_EQ(ErrorOf(tmp / "a" / "b"), "");
}

TEST(RunOutputDir, AnEarlierRunNeedsOverwriteAndIsThenRemovedWhole) {
  testing::TempDir tmp;
  const fs::path dir = tmp / "out";
  { RunOutputDir out(dir); }
  std::ofstream(dir / "run.json") << "{}";
  fs::create_directories(dir / "plots");
  std::ofstream(dir / "plots" / "landmarks.png") << "png";
  const std::string refused = ErrorOf(dir);
  EXPECT_NE(refused.find("--overwrite"), std::string::npos) << refused;
  EXPECT_TRUE(fs::exists(dir / "run.json"));
  OutputDirOptions overwrite;
  overwrite.overwrite = true;
  RunOutputDir out(dir, overwrite);
  EXPECT_EQ(out.removed_entries(), 2u);
  EXPECT_FALSE(fs::exists(dir / "run.json"));
  EXPECT_FALSE(fs::exists(dir / "plots"));
}

TEST(RunOutputDir, AFolderOfOtherFilesIsNeverEmptied) {
  testing::TempDir tmp;
  const fs::path dir = tmp / "home";
  fs::create_directories(dir);
  std::ofstream(dir / "thesis.tex") << "precious";
  OutputDirOptions overwrite;
  overwrite.overwrite = true;
  const std::string refused = ErrorOf(dir, overwrite);
  EXPECT_NE(refused.find("holds no semslam outputs"), std::string::npos) << refused;
  EXPECT_TRUE(fs::exists(dir / "thesis.tex"));
  EXPECT_FALSE(fs::exists(dir / kOutputLockFile)) << "the folder is left as it was";
}

TEST(RunOutputDir, AFolderHoldingAnInputIsNeverEmptied) {
  testing::TempDir tmp;
  const fs::path dir = tmp / "out";
  { RunOutputDir out(dir); }
  std::ofstream(dir / "run.json") << "{}";
  std::ofstream(dir / "map.semslam") << "map";
  OutputDirOptions overwrite;
  overwrite.overwrite = true;
  // The input named the way a user types it: through a relative detour.
  overwrite.inputs = {fs::path(), tmp / "elsewhere.csv", tmp / "out" / ".." / "out" / "map.semslam"};
  const std::string refused = ErrorOf(dir, overwrite);
  EXPECT_NE(refused.find("map.semslam, which this run reads"), std::string::npos) << refused;
  EXPECT_TRUE(fs::exists(dir / "map.semslam"));
  EXPECT_TRUE(fs::exists(dir / "run.json"));
  // The folder itself as an input (a merge given its own output), and an input beside it.
  overwrite.inputs = {dir};
  EXPECT_NE(ErrorOf(dir, overwrite).find("which this run reads"), std::string::npos);
  overwrite.inputs = {tmp / "out2" / "map.semslam"};
  EXPECT_EQ(ErrorOf(dir, overwrite), "");
  EXPECT_FALSE(fs::exists(dir / "map.semslam"));
}

TEST(RunOutputDir, ASecondWriterIsRefused) {
  testing::TempDir tmp;
  const fs::path dir = tmp / "out";
  RunOutputDir first(dir);
  // flock locks belong to the open file: a second open in this process conflicts like another process.
  const std::string refused = ErrorOf(dir);
  EXPECT_NE(refused.find("another semslam command"), std::string::npos) << refused;
  EXPECT_NE(refused.find("pid " + std::to_string(::getpid())), std::string::npos) << refused;
}

TEST(RunOutputDir, StaleTemporaryFilesAreRemoved) {
  testing::TempDir tmp;
  const fs::path dir = tmp / "out";
  { RunOutputDir out(dir); }
  std::ofstream(dir / ".run.json.tmp999999999.4") << "partial";  // a writer killed mid-write
  EXPECT_EQ(ErrorOf(dir), "");                                     // no --overwrite needed
  EXPECT_FALSE(fs::exists(dir / ".run.json.tmp999999999.4"));
}

TEST(RunOutputDir, UnusableFoldersGiveTheSystemReasonBeforeAnyWork) {
  testing::TempDir tmp;
  std::ofstream(tmp / "file") << "x";
  const std::string not_a_dir = ErrorOf(tmp / "file" / "out");
  EXPECT_NE(not_a_dir.find("Not a directory"), std::string::npos) << not_a_dir;
  const std::string is_a_file = ErrorOf(tmp / "file");
  EXPECT_NE(is_a_file.find("Not a directory"), std::string::npos) << is_a_file;
  OutputDirOptions huge;
  huge.min_free_bytes = std::uint64_t{1} << 62;  // more than any disk has
  const std::string full = ErrorOf(tmp / "out", huge);
  EXPECT_NE(full.find("No space left on device"), std::string::npos) << full;
  if (::geteuid() != 0) {  // root writes anywhere
    fs::create_directories(tmp / "readonly");
    fs::permissions(tmp / "readonly", fs::perms::owner_read | fs::perms::owner_exec);
    const std::string denied = ErrorOf(tmp / "readonly" / "out");
    EXPECT_NE(denied.find("Permission denied"), std::string::npos) << denied;
    fs::permissions(tmp / "readonly", fs::perms::owner_all);
  }
}

}  // namespace
}  // namespace semslam
