// `semslam synth` is deterministic (sim/dataset_writer.h: "the same options give the same bytes"): two runs
// with the same arguments write identical files, and another seed writes different images.

#include <gtest/gtest.h>

#include <map>

#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

// Every regular file under `root`, by relative path.
std::map<std::string, fs::path> Files(const fs::path& root) {
  std::map<std::string, fs::path> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (entry.is_regular_file()) files[fs::relative(entry.path(), root).string()] = entry.path();
  }
  return files;
}

TEST(Synth, SameArgumentsGiveIdenticalFiles) {
  SEMSLAM_REQUIRE_BINARY();
  testing::TempDir dir;
  const auto synth = [&](const fs::path& out, const std::string& seed = "7") {
    return RunSemslam({"synth", "--out", out.string(), "--frames", "4", "--seed", seed, "--gps-noise", "2",
                       "--gps-every", "2", "-q"});
  };
  const CommandResult a = synth(dir / "a");
  ASSERT_TRUE(a.Succeeded()) << a.Describe();
  const CommandResult b = synth(dir / "b");
  ASSERT_TRUE(b.Succeeded()) << b.Describe();
  const auto files_a = Files(dir / "a"), files_b = Files(dir / "b");
  ASSERT_GE(files_a.size(), 4u * 4 + 6);  // 4 frames x 4 images, calib, times, poses, oxts, landmarks, scene
  for (const char* file : {"sequences/00/calib.txt", "sequences/00/times.txt",
                           "sequences/00/image_0/000003.png", "sequences/00/image_1/000003.png",
                           "sequences/00/label_0/000003.png", "sequences/00/depth_0/000003.png",
                           "poses/00.txt", "oxts/timestamps.txt", "landmarks.csv", "scene.json"}) {
    EXPECT_TRUE(files_a.count(file)) << file;
  }
  ASSERT_EQ(files_a.size(), files_b.size());
  for (const auto& [name, path] : files_a) {
    ASSERT_TRUE(files_b.count(name)) << name;
    EXPECT_TRUE(SameBytes(path, files_b.at(name))) << name << " differs between two identical runs";
  }

  // A different town seed changes the images (so the comparison above can fail).
  const CommandResult c = synth(dir / "c", "8");
  ASSERT_TRUE(c.Succeeded()) << c.Describe();
  EXPECT_FALSE(SameBytes(dir / "a" / "sequences/00/image_0/000003.png",
                         dir / "c" / "sequences/00/image_0/000003.png"));
}

}  // namespace
}  // namespace semslam::system_test
