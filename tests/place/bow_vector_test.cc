#include "semslam/place/bow_vector.h"

#include <gtest/gtest.h>

namespace semslam {
namespace {

TEST(BowVector, SortsMergesAndNormalizes) {
  BowVector v({{7, 1.0}, {2, 2.0}, {7, 3.0}});
  ASSERT_EQ(v.size(), 2u);
  EXPECT_EQ(v.entries()[0], (BowVector::Entry{2, 2.0}));
  EXPECT_EQ(v.entries()[1], (BowVector::Entry{7, 4.0}));
  EXPECT_DOUBLE_EQ(v.Weight(7), 4.0);
  EXPECT_DOUBLE_EQ(v.Weight(3), 0.0);
  EXPECT_DOUBLE_EQ(v.L1Norm(), 6.0);
  v.NormalizeL1();
  EXPECT_DOUBLE_EQ(v.Weight(2), 1.0 / 3.0);
  EXPECT_DOUBLE_EQ(v.L1Norm(), 1.0);
  BowVector empty;
  empty.NormalizeL1();
  EXPECT_TRUE(empty.empty());
}

TEST(ScoreL1, KnownAnswers) {
  const BowVector a({{1, 0.5}, {2, 0.5}});
  const BowVector b({{2, 0.5}, {3, 0.5}});
  const BowVector c({{4, 1.0}});
  const BowVector d({{1, 0.2}, {2, 0.8}});
  EXPECT_DOUBLE_EQ(ScoreL1(a, a), 1.0);
  EXPECT_DOUBLE_EQ(ScoreL1(a, b), 0.5);
  EXPECT_DOUBLE_EQ(ScoreL1(b, a), 0.5);
  EXPECT_DOUBLE_EQ(ScoreL1(a, c), 0.0);
  // 1 - |a - d|_1 / 2 = 1 - (0.3 + 0.3) / 2 = 0.7.
  EXPECT_DOUBLE_EQ(ScoreL1(a, d), 0.7);
  EXPECT_DOUBLE_EQ(ScoreL1(a, BowVector()), 0.0);
}

}  // namespace
}  // namespace semslam
