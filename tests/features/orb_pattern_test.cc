#include "semslam/features/orb_pattern.h"

#include <gtest/gtest.h>

#include <set>
#include <tuple>

namespace semslam {
namespace {

TEST(BriefPattern, PointsLieInTheDiscAndTestsAreDistinct) {
  const BriefPattern& p = SemslamBriefPattern();
  std::set<std::tuple<int, int, int, int>> seen;
  for (const BriefPair& q : p) {
    EXPECT_LE(q.x1 * q.x1 + q.y1 * q.y1, kBriefPatternRadius * kBriefPatternRadius);
    EXPECT_LE(q.x2 * q.x2 + q.y2 * q.y2, kBriefPatternRadius * kBriefPatternRadius);
    EXPECT_FALSE(q.x1 == q.x2 && q.y1 == q.y2);
    EXPECT_TRUE(seen.insert({q.x1, q.y1, q.x2, q.y2}).second);
    EXPECT_EQ(seen.count({q.x2, q.y2, q.x1, q.y1}), 0u);  // not the same test negated
  }
}

TEST(BriefPattern, StoredTableIsWhatTheLearningProcedureGives) {
  // Reproduces orb_pattern_table.inc from its documented recipe (takes a few seconds).
  PatternLearningStats stats;
  const BriefPattern learned = LearnBriefPattern(PatternLearningOptions{}, &stats);
  EXPECT_EQ(learned, SemslamBriefPattern())
      << "regenerate orb_pattern_table.inc with FormatBriefPatternTable";
  EXPECT_GT(stats.training_patches, 20000);
  // Less biased and less correlated than the same number of plain Gaussian tests.
  std::vector<BriefPair> gaussian = GenerateGaussianPairs(99, 256);
  BriefPattern plain{};
  std::copy(gaussian.begin(), gaussian.end(), plain.begin());
  const PatternLearningStats plain_stats = EvaluateBriefPattern(plain, PatternLearningOptions{});
  EXPECT_LT(stats.mean_abs_bias, plain_stats.mean_abs_bias);
  EXPECT_LT(stats.mean_abs_correlation, plain_stats.mean_abs_correlation);
}

TEST(BriefPattern, RandomNumbersAreDeterministic) {
  PatternRandom a(1), b(1);
  for (int i = 0; i < 10; ++i) EXPECT_EQ(a.Next(), b.Next());
  EXPECT_EQ(GenerateGaussianPairs(3, 50), GenerateGaussianPairs(3, 50));
  const cv::Mat x = MakeSyntheticTrainingImage(8), y = MakeSyntheticTrainingImage(8);
  EXPECT_EQ(cv::norm(x, y, cv::NORM_L1), 0.0);
}

}  // namespace
}  // namespace semslam
