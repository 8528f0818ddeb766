// `semslam vocab ...` end to end through the built binary.

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "semslam/features/orb_pattern.h"
#include "semslam/place/vocabulary.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using testing::CommandResult;
using testing::RunSemslam;

// `semslam vocab` reports on stderr.
TEST(VocabCli, TrainConvertAndInfo) {
  SEMSLAM_REQUIRE_BINARY();
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "images");
  for (int i = 0; i < 12; ++i) {
    cv::imwrite((dir / "images" / (std::to_string(100 + i) + ".png")).string(),
                MakeSyntheticTrainingImage(300 + i));
  }
  CommandResult r =
      RunSemslam({"vocab", "train", "--images", (dir / "images").string(), "--out", (dir / "v.voc").string(),
                  "--k", "4", "--levels", "3", "--features", "300", "--max-images", "10"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_NE(r.err.find("10 images"), std::string::npos) << r.err;
  const Vocabulary v = Vocabulary::Load(dir / "v.voc");
  EXPECT_EQ(v.branching(), 4);
  EXPECT_EQ(v.depth(), 3);
  EXPECT_GT(v.size(), 40u);
  r = RunSemslam({"vocab", "info", (dir / "v.voc").string()});
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.err.find("k = 4, L = 3"), std::string::npos) << r.err;

  // A DBoW2 text file converts to the same vocabulary as loading it directly.
  {
    std::ofstream tiny(dir / "tiny.txt");
    tiny << "2 1 0 0\n0 1";
    for (int i = 0; i < 32; ++i) tiny << " 0";
    tiny << " 1.5\n0 1";
    for (int i = 0; i < 32; ++i) tiny << " 255";
    tiny << " 0.5\n";
  }
  r = RunSemslam(
      {"vocab", "convert", "--dbow2", (dir / "tiny.txt").string(), "--out", (dir / "tiny.voc").string()});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_EQ(Vocabulary::Load(dir / "tiny.voc"), Vocabulary::LoadDbow2Text(dir / "tiny.txt"));

  // Errors: a one-line reason, non-zero status.
  r = RunSemslam(
      {"vocab", "train", "--images", (dir / "nowhere").string(), "--out", (dir / "x.voc").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("nowhere"), std::string::npos) << r.err;
  std::ofstream(dir / "broken.txt") << "2 1 0 0\n0 1 5\n";
  r = RunSemslam(
      {"vocab", "convert", "--dbow2", (dir / "broken.txt").string(), "--out", (dir / "y.voc").string()});
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.err.find("broken.txt:2"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "y.voc"));
}

}  // namespace
}  // namespace semslam
