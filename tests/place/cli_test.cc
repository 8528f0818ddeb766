// `semslam vocab ...` end to end through the built binary.

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "semslam/features/orb_pattern.h"
#include "semslam/place/vocabulary.h"
#include "support/test_support.h"

namespace semslam {
namespace {

int RunSemslam(const std::string& args, const std::filesystem::path& log) {
  const std::string command = testing::SemslamBinary().string() + " " + args + " > " + log.string() + " 2>&1";
  return std::system(command.c_str());
}

std::string Read(const std::filesystem::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(VocabCli, TrainConvertAndInfo) {
  if (!std::filesystem::exists(testing::SemslamBinary())) GTEST_SKIP() << "semslam binary not built";
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "images");
  for (int i = 0; i < 12; ++i) {
    cv::imwrite((dir / "images" / (std::to_string(100 + i) + ".png")).string(),
                MakeSyntheticTrainingImage(300 + i));
  }
  const auto log = dir / "log.txt";
  ASSERT_EQ(RunSemslam("vocab train --images " + (dir / "images").string() + " --out " +
                           (dir / "v.voc").string() + " --k 4 --levels 3 --features 300 --max-images 10",
                       log),
            0)
      << Read(log);
  EXPECT_NE(Read(log).find("10 images"), std::string::npos) << Read(log);
  const Vocabulary v = Vocabulary::Load(dir / "v.voc");
  EXPECT_EQ(v.branching(), 4);
  EXPECT_EQ(v.depth(), 3);
  EXPECT_GT(v.size(), 40u);
  EXPECT_EQ(RunSemslam("vocab info " + (dir / "v.voc").string(), log), 0);
  EXPECT_NE(Read(log).find("k = 4, L = 3"), std::string::npos) << Read(log);

  // A DBoW2 text file converts to the same vocabulary as loading it directly.
  {
    std::ofstream tiny(dir / "tiny.txt");
    tiny << "2 1 0 0\n0 1";
    for (int i = 0; i < 32; ++i) tiny << " 0";
    tiny << " 1.5\n0 1";
    for (int i = 0; i < 32; ++i) tiny << " 255";
    tiny << " 0.5\n";
  }
  ASSERT_EQ(RunSemslam("vocab convert --dbow2 " + (dir / "tiny.txt").string() + " --out " +
                           (dir / "tiny.voc").string(),
                       log),
            0)
      << Read(log);
  EXPECT_EQ(Vocabulary::Load(dir / "tiny.voc"), Vocabulary::LoadDbow2Text(dir / "tiny.txt"));

  // Errors: a one-line reason, non-zero status.
  EXPECT_NE(
      RunSemslam("vocab train --images " + (dir / "nowhere").string() + " --out " + (dir / "x.voc").string(),
                 log),
      0);
  EXPECT_NE(Read(log).find("nowhere"), std::string::npos) << Read(log);
  std::ofstream(dir / "broken.txt") << "2 1 0 0\n0 1 5\n";
  EXPECT_NE(RunSemslam("vocab convert --dbow2 " + (dir / "broken.txt").string() + " --out " +
                           (dir / "y.voc").string(),
                       log),
            0);
  EXPECT_NE(Read(log).find("broken.txt:2"), std::string::npos) << Read(log);
  EXPECT_FALSE(std::filesystem::exists(dir / "y.voc"));
}

}  // namespace
}  // namespace semslam
