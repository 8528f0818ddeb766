// Which keyframes of the map look like a query.
#include "semslam/map/place_candidates.h"

#include <gtest/gtest.h>

#include "map_test_frames.h"

namespace semslam {
namespace {

// Equal weights on the words [first, last) of each range.
BowVector UniformWords(const std::vector<std::pair<WordId, WordId>>& ranges) {
  std::vector<BowVector::Entry> entries;
  for (const auto& [first, last] : ranges) {
    for (WordId w = first; w < last; ++w) entries.emplace_back(w, 1.0);
  }
  BowVector bow(std::move(entries));
  bow.NormalizeL1();
  return bow;
}

TEST(FindPlaceCandidates, AKeyFrameWithManyMoreWordsDoesNotCrowdOutThePlace) {
  // The query (400 words) is the place's keyframe's place: it shares 150 of its 200 words. A keyframe with
  // five times the words (a map's first keyframes are extracted with more features) shares more of them,
  // 200, by their number alone: 20 % of its words, and a lower score.
  Map map;
  KeyFrameDatabase database(10000);
  KeyFrame *place = nullptr, *many_words = nullptr;
  {
    auto lock = map.WriteLock();
    place = map.AddKeyFrame(MakeFrame(0, 50, false, {0, 0, 0}));
    many_words = map.AddKeyFrame(MakeFrame(1, 50, false, {0, 0, 50}));
  }
  place->bow = UniformWords({{0, 150}, {5000, 5050}});
  many_words->bow = UniformWords({{200, 400}, {6000, 6800}});
  for (KeyFrame* kf : {place, many_words}) {
    kf->has_bow = true;
    database.Add(kf->id(), kf->bow);
  }
  const BowVector query = UniformWords({{0, 400}});

  auto lock = map.ReadLock();
  const std::vector<KeyFrame*> candidates = FindPlaceCandidates(query, database, map);
  ASSERT_EQ(candidates.size(), 1u);
  EXPECT_EQ(candidates.front(), place);
}

TEST(FindPlaceCandidates, KeepsToTheMapAndLeavesOutTheExcluded) {
  Map map;
  KeyFrameDatabase database(10000);
  std::vector<KeyFrame*> kfs;
  {
    auto lock = map.WriteLock();
    for (int i = 0; i < 3; ++i) {
      if (i == 2) map.StartNewMap();
      kfs.push_back(map.AddKeyFrame(MakeFrame(i, 50, false, {0, 0, 10.0 * i})));
    }
  }
  for (KeyFrame* kf : kfs) {
    kf->bow = UniformWords({{0, 100}});
    kf->has_bow = true;
    database.Add(kf->id(), kf->bow);
  }
  auto lock = map.ReadLock();
  PlaceCandidateOptions options;
  options.excluded = {kfs[0]->id()};
  options.map_id = kfs[0]->map_id();
  EXPECT_EQ(FindPlaceCandidates(UniformWords({{0, 100}}), database, map, options),
            std::vector<KeyFrame*>{kfs[1]});
  options = {};
  options.excluded_maps = {kfs[0]->map_id()};
  EXPECT_EQ(FindPlaceCandidates(UniformWords({{0, 100}}), database, map, options),
            std::vector<KeyFrame*>{kfs[2]});
}

}  // namespace
}  // namespace semslam
