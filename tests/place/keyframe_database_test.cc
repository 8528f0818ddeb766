#include "semslam/place/keyframe_database.h"

#include <gtest/gtest.h>

#include <random>
#include <thread>

#include "semslam/core/error.h"

namespace semslam {
namespace {

BowVector RandomBow(std::mt19937& rng, int words, int vocabulary) {
  std::uniform_int_distribution<int> word(0, vocabulary - 1);
  std::uniform_real_distribution<double> weight(0.1, 1.0);
  std::vector<BowVector::Entry> e;
  for (int i = 0; i < words; ++i) {
    const double w = weight(rng);  // before the word, as GCC drew them (support/draws.h)
    e.emplace_back(static_cast<WordId>(word(rng)), w);
  }
  BowVector v(std::move(e));
  v.NormalizeL1();
  return v;
}

int SharedWords(const BowVector& a, const BowVector& b) {
  int n = 0;
  for (const auto& [w, x] : a) n += b.Weight(w) > 0;
  return n;
}

TEST(KeyFrameDatabase, QueryScoresEqualTheL1ScoreAndTheImageFindsItself) {
  std::mt19937 rng(3);
  KeyFrameDatabase db(1000);
  std::vector<BowVector> bows;
  for (int i = 0; i < 60; ++i) {
    bows.push_back(RandomBow(rng, 80, 1000));
    db.Add(static_cast<std::uint64_t>(100 + i), bows.back());
  }
  EXPECT_EQ(db.size(), 60u);
  for (int i = 0; i < 60; ++i) {
    const auto results = db.Query(bows[static_cast<size_t>(i)]);
    ASSERT_FALSE(results.empty());
    EXPECT_EQ(results[0].id, static_cast<std::uint64_t>(100 + i));
    EXPECT_NEAR(results[0].score, 1.0, 1e-12);
    for (size_t k = 0; k < results.size(); ++k) {
      const auto& other = bows[results[k].id - 100];
      EXPECT_EQ(results[k].score, ScoreL1(bows[static_cast<size_t>(i)], other));  // exactly
      EXPECT_EQ(results[k].shared_words, SharedWords(bows[static_cast<size_t>(i)], other));
      if (k > 0) {
        EXPECT_LE(results[k].score, results[k - 1].score);
      }
    }
  }
}

TEST(KeyFrameDatabase, EraseReplaceFilterAndLimits) {
  KeyFrameDatabase db(10);
  const BowVector a({{1, 0.5}, {2, 0.5}}), b({{2, 0.5}, {3, 0.5}}), c({{7, 1.0}});
  db.Add(1, a);
  db.Add(2, b);
  db.Add(3, c);
  auto r = db.Query(a);
  ASSERT_EQ(r.size(), 2u);  // 3 shares no word
  EXPECT_EQ(r[0].id, 1u);
  EXPECT_EQ(r[1].id, 2u);
  EXPECT_DOUBLE_EQ(r[1].score, 0.5);
  EXPECT_EQ(r[1].shared_words, 1);
  DatabaseQueryOptions options;
  options.filter = [](std::uint64_t id) { return id != 1; };
  r = db.Query(a, options);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].id, 2u);
  options = {};
  options.min_shared_words = 2;
  EXPECT_EQ(db.Query(a, options).size(), 1u);
  options = {};
  options.max_results = 1;
  EXPECT_EQ(db.Query(a, options).size(), 1u);
  options = {};
  options.min_score = 0.6;
  EXPECT_EQ(db.Query(a, options).size(), 1u);
  db.Erase(1);
  EXPECT_FALSE(db.Contains(1));
  r = db.Query(a);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].id, 2u);
  db.Erase(42);  // unknown: ignored
  db.Add(2, c);  // replaces
  EXPECT_TRUE(db.Query(a).empty());
  EXPECT_EQ(db.Query(c).size(), 2u);
  EXPECT_EQ(db.size(), 2u);
  EXPECT_THROW(db.Add(5, BowVector({{10, 1.0}})), InvalidArgument);
  db.Clear();
  EXPECT_EQ(db.size(), 0u);
  EXPECT_TRUE(db.Query(c).empty());
}

TEST(KeyFrameDatabase, ConcurrentAddEraseQuery) {
  KeyFrameDatabase db(500);
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&db, t] {
      std::mt19937 rng(static_cast<unsigned>(t));
      for (int i = 0; i < 300; ++i) {
        const BowVector bow = RandomBow(rng, 50, 500);
        const std::uint64_t id = static_cast<std::uint64_t>(t * 1000 + i);
        db.Add(id, bow);
        const auto r = db.Query(bow);
        ASSERT_FALSE(r.empty());
        EXPECT_NEAR(r[0].score, 1.0, 1e-12);
        if (i % 3 == 0) db.Erase(id);
      }
    });
  }
  for (auto& t : threads) t.join();
  EXPECT_EQ(db.size(), 4u * 200u);
}

}  // namespace
}  // namespace semslam
