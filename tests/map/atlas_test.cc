// The map as an atlas: sessions (drives) and several maps, each with its own origin, merged or discarded.

#include <gtest/gtest.h>

#include "map_test_frames.h"
#include "semslam/map/map.h"
#include "semslam/map/map_file.h"
#include "support/test_support.h"

namespace semslam {
namespace {

// Adds a keyframe at `z` with `n_points` points of its own, in the active map.
KeyFrame* AddKeyFrameWithPoints(Map& map, std::uint64_t id, double z, int n_points) {
  KeyFrame* kf = map.AddKeyFrame(MakeFrame(id, 100, /*stereo=*/false, {0, 0, z}));
  for (int i = 0; i < n_points; ++i) {
    MapPoint* p = map.AddMapPoint(Eigen::Vector3d(0.1 * i, 0.0, z + 10.0), kf);
    p->AddObservation(kf, i);
    kf->SetMapPoint(i, p);
  }
  return kf;
}

// Makes `kf` observe `n` points of `seen` (its first ones), at keypoints `first_index` on.
void ObservePointsOf(KeyFrame* kf, const KeyFrame* seen, int n, int first_index) {
  for (int i = 0; i < n; ++i) {
    MapPoint* p = seen->map_point(i);
    p->AddObservation(kf, first_index + i);
    kf->SetMapPoint(first_index + i, p);
  }
}

TEST(Atlas, ANewMapIsSessionZeroAndMapZeroWithItsFirstKeyFrameAsOrigin) {
  Map map;
  auto lock = map.WriteLock();
  KeyFrame* a = AddKeyFrameWithPoints(map, 0, 0.0, 5);
  KeyFrame* b = AddKeyFrameWithPoints(map, 1, 1.0, 5);
  EXPECT_EQ(map.sessions().size(), 1u);
  EXPECT_EQ(a->session(), 0u);
  EXPECT_EQ(a->map_id(), 0u);
  EXPECT_TRUE(a->is_map_origin());
  EXPECT_FALSE(b->is_map_origin());
  EXPECT_EQ(map.MapIds(), std::vector<std::uint32_t>{0});
}

TEST(Atlas, ANewMapHasItsOwnOriginAndItsOwnKeyFramesAndPoints) {
  Map map;
  auto lock = map.WriteLock();
  AddKeyFrameWithPoints(map, 0, 0.0, 5);
  AddKeyFrameWithPoints(map, 1, 1.0, 5);
  EXPECT_EQ(map.StartNewMap(), 1u);
  KeyFrame* c = AddKeyFrameWithPoints(map, 2, 2.0, 3);
  AddKeyFrameWithPoints(map, 3, 3.0, 3);
  EXPECT_EQ(c->map_id(), 1u);
  EXPECT_TRUE(c->is_map_origin());
  EXPECT_EQ(map.MapIds(), (std::vector<std::uint32_t>{0, 1}));
  EXPECT_EQ(map.NumKeyFramesOfMap(0), 2u);
  EXPECT_EQ(map.NumKeyFramesOfMap(1), 2u);
  EXPECT_EQ(map.MapPointsOfMap(0).size(), 10u);
  EXPECT_EQ(map.MapPointsOfMap(1).size(), 6u);
  for (const MapPoint* p : map.MapPointsOfMap(1)) EXPECT_EQ(p->map_id(), 1u);

  map.ActivateMap(0);
  EXPECT_FALSE(AddKeyFrameWithPoints(map, 4, 4.0, 1)->is_map_origin());
  EXPECT_EQ(map.NumKeyFramesOfMap(0), 3u);
}

TEST(Atlas, MergingMovesEveryKeyFrameAndPointAndLeavesOneOrigin) {
  Map map;
  auto lock = map.WriteLock();
  AddKeyFrameWithPoints(map, 0, 0.0, 5);
  map.StartNewMap();
  KeyFrame* c = AddKeyFrameWithPoints(map, 1, 5.0, 4);
  map.MergeMapInto(1, 0);
  EXPECT_EQ(map.active_map_id(), 0u);
  EXPECT_EQ(c->map_id(), 0u);
  EXPECT_FALSE(c->is_map_origin());
  EXPECT_EQ(map.MapIds(), std::vector<std::uint32_t>{0});
  EXPECT_EQ(map.MapPointsOfMap(0).size(), 9u);
  size_t origins = 0;
  for (const KeyFrame* kf : map.KeyFramesOfMap(0)) origins += kf->is_map_origin() ? 1 : 0;
  EXPECT_EQ(origins, 1u);
  // A new map after a merge gets a fresh id; ids are never reused.
  EXPECT_EQ(map.StartNewMap(), 2u);
}

TEST(Atlas, AGapLinkStandsBetweenTheGoodKeyFramesForItsEnds) {
  // before (kf 1, its parent kf 0) in map 0; after (kf 3, its parent kf 2) in map 1. Culling both ends hands
  // the link to their parents, through the poses relative to them that culling keeps.
  Map map;
  auto lock = map.WriteLock();
  KeyFrame* k0 = AddKeyFrameWithPoints(map, 0, 0.0, 3);
  KeyFrame* before = AddKeyFrameWithPoints(map, 1, 1.0, 3);
  map.StartNewMap();
  KeyFrame* k2 = AddKeyFrameWithPoints(map, 2, 0.0, 3);
  KeyFrame* after = AddKeyFrameWithPoints(map, 3, 2.0, 3);
  before->ChangeParent(k0);
  after->ChangeParent(k2);
  before->SetPose(Rigid3d(QuaternionExp(Eigen::Vector3d(0, 0.2, 0)), Eigen::Vector3d(0.5, 0, -1.0)));
  after->SetPose(Rigid3d(QuaternionExp(Eigen::Vector3d(0.1, -0.3, 0)), Eigen::Vector3d(0, 0.2, -2.0)));
  const Rigid3d after_from_before(QuaternionExp(Eigen::Vector3d(0, -0.4, 0.05)), Eigen::Vector3d(1, 0, -3));
  const GapLink link{before, after, after_from_before};

  std::optional<GapEdge> edge = ResolveGapLink(link);
  ASSERT_TRUE(edge.has_value());
  EXPECT_EQ(edge->before, before);
  EXPECT_EQ(edge->after, after);
  EXPECT_LT((edge->before_from_after.translation - after_from_before.Inverse().translation).norm(), 1e-12);

  // A monocular loop that stretches the map around `before` twice as large stretches the link with it.
  before->CorrectScale(2.0);
  edge = ResolveGapLink(link);
  ASSERT_TRUE(edge.has_value());
  EXPECT_LT((edge->before_from_after.translation - 2.0 * after_from_before.Inverse().translation).norm(),
            1e-12);
  before->CorrectScale(0.5);

  // k0 and k2 stand in for the culled ends: k0_from_k2 = k0_from_before * before_from_after * after_from_k2.
  const Rigid3d expected = k0->camera_from_world() * before->world_from_camera() *
                           after_from_before.Inverse() * after->camera_from_world() * k2->world_from_camera();
  before->SetBad();
  after->SetBad();
  edge = ResolveGapLink(link);
  ASSERT_TRUE(edge.has_value());
  EXPECT_EQ(edge->before, k0);
  EXPECT_EQ(edge->after, k2);
  EXPECT_LT((edge->before_from_after.translation - expected.translation).norm(), 1e-9);
  EXPECT_LT(edge->before_from_after.rotation.angularDistance(expected.rotation), 1e-9);

  // A map given up (its keyframes bad without parents) leaves the link without an end.
  map.DiscardMap(1);
  EXPECT_FALSE(ResolveGapLink(link).has_value());
}

TEST(Atlas, DiscardingAMapErasesOnlyItsKeyFramesAndPoints) {
  Map map;
  auto lock = map.WriteLock();
  AddKeyFrameWithPoints(map, 0, 0.0, 5);
  map.StartNewMap();
  KeyFrame* young = AddKeyFrameWithPoints(map, 1, 5.0, 4);
  map.DiscardMap(1);
  EXPECT_TRUE(young->is_bad());
  EXPECT_EQ(map.NumKeyFrames(), 1u);
  EXPECT_EQ(map.NumMapPoints(), 5u);
  EXPECT_EQ(map.MapIds(), std::vector<std::uint32_t>{0});
}

TEST(Atlas, SessionsNumberTheDrivesAndTagTheirKeyFrames) {
  Map map;
  auto lock = map.WriteLock();
  map.NameCurrentSession("07", "/data/07");
  AddKeyFrameWithPoints(map, 0, 0.0, 2);
  EXPECT_EQ(map.BeginSession("07 again", "/data/07"), 1u);
  KeyFrame* second = AddKeyFrameWithPoints(map, 1, 0.0, 2);
  EXPECT_EQ(second->session(), 1u);
  ASSERT_EQ(map.sessions().size(), 2u);
  EXPECT_EQ(map.sessions()[0].name, "07");
  EXPECT_EQ(map.sessions()[1].name, "07 again");
  EXPECT_THROW(map.RestoreSessions({{1, "x", "y"}}), InvalidArgument);
}

TEST(Atlas, TheMapFileKeepsSessionsMapsAndOrigins) {
  testing::TempDir dir;
  Map map;
  {
    auto lock = map.WriteLock();
    map.NameCurrentSession("first", "/a");
    AddKeyFrameWithPoints(map, 0, 0.0, 3);
    AddKeyFrameWithPoints(map, 1, 1.0, 3);
    map.BeginSession("second", "/b");
    map.StartNewMap();
    AddKeyFrameWithPoints(map, 2, 2.0, 3);
    AddKeyFrameWithPoints(map, 3, 3.0, 3);
    for (KeyFrame* kf : map.KeyFrames()) kf->UpdateConnections();
  }
  const auto path = dir / "map.semslam";
  {
    auto lock = map.ReadLock();
    WriteMapFile(path, map);
  }
  Map loaded;
  auto lock = loaded.WriteLock();
  ReadMapFile(path, loaded);
  ASSERT_EQ(loaded.sessions().size(), 2u);
  EXPECT_EQ(loaded.sessions()[1].name, "second");
  EXPECT_EQ(loaded.sessions()[1].source, "/b");
  EXPECT_EQ(loaded.active_map_id(), 1u);
  EXPECT_EQ(loaded.next_map_id(), 2u);
  const auto kfs = loaded.KeyFrames();
  ASSERT_EQ(kfs.size(), 4u);
  const std::vector<std::uint32_t> sessions = {0, 0, 1, 1}, maps = {0, 0, 1, 1};
  const std::vector<bool> origins = {true, false, true, false};
  for (size_t k = 0; k < kfs.size(); ++k) {
    EXPECT_EQ(kfs[k]->session(), sessions[k]) << k;
    EXPECT_EQ(kfs[k]->map_id(), maps[k]) << k;
    EXPECT_EQ(kfs[k]->is_map_origin(), origins[k]) << k;
  }
  // The loaded atlas goes on numbering maps after the stored ones.
  EXPECT_EQ(loaded.StartNewMap(), 2u);
}

TEST(Atlas, AMapFileAppendedToAnotherMapBecomesMoreSessionsAndMapsOfIt) {
  testing::TempDir dir;
  // Two drives, saved apart: the first with one map, the second with two (each file numbers from 0).
  const auto first_path = dir / "first.semslam", second_path = dir / "second.semslam";
  {
    Map map;
    auto lock = map.WriteLock();
    map.NameCurrentSession("first", "/a");
    KeyFrame* a = AddKeyFrameWithPoints(map, 0, 0.0, 4);
    KeyFrame* b = AddKeyFrameWithPoints(map, 1, 1.0, 0);
    ObservePointsOf(b, a, 4, 0);
    for (KeyFrame* kf : map.KeyFrames()) kf->UpdateConnections();
    WriteMapFile(first_path, map);
  }
  {
    Map map;
    auto lock = map.WriteLock();
    map.NameCurrentSession("second", "/b");
    KeyFrame* a = AddKeyFrameWithPoints(map, 0, 5.0, 3);
    KeyFrame* b = AddKeyFrameWithPoints(map, 1, 6.0, 0);
    ObservePointsOf(b, a, 3, 0);
    map.StartNewMap();
    AddKeyFrameWithPoints(map, 2, 9.0, 2);
    for (KeyFrame* kf : map.KeyFrames()) kf->UpdateConnections();
    WriteMapFile(second_path, map);
  }
  Map atlas;
  auto lock = atlas.WriteLock();
  const MapFileContents first = AppendMapFile(first_path, atlas);  // into an empty map: as ReadMapFile
  EXPECT_EQ(first.first_session, 0u);
  EXPECT_EQ(first.first_map_id, 0u);
  const MapFileContents second = AppendMapFile(second_path, atlas);
  EXPECT_EQ(second.first_session, 1u);
  EXPECT_EQ(second.first_map_id, 1u);
  ASSERT_EQ(atlas.sessions().size(), 2u);
  EXPECT_EQ(atlas.sessions()[0].name, "first");
  EXPECT_EQ(atlas.sessions()[1].name, "second");
  EXPECT_EQ(atlas.sessions()[1].id, 1u);
  EXPECT_EQ(atlas.MapIds(), (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(atlas.next_map_id(), 3u);
  // Cameras by the atlas's map ids.
  EXPECT_EQ(second.cameras.size(), 2u);
  EXPECT_TRUE(second.cameras.count(1) && second.cameras.count(2));
  const auto kfs = atlas.KeyFrames();
  ASSERT_EQ(kfs.size(), 5u);
  const std::vector<std::uint64_t> ids = {0, 1, 2, 3, 4};
  const std::vector<std::uint32_t> sessions = {0, 0, 1, 1, 1}, maps = {0, 0, 1, 1, 2};
  for (size_t k = 0; k < kfs.size(); ++k) {
    EXPECT_EQ(kfs[k]->id(), ids[k]) << k;
    EXPECT_EQ(kfs[k]->session(), sessions[k]) << k;
    EXPECT_EQ(kfs[k]->map_id(), maps[k]) << k;
  }
  // Points, observations and the spanning tree stay within their own file's keyframes.
  EXPECT_EQ(atlas.NumMapPoints(), 4u + 3u + 2u);
  EXPECT_EQ(atlas.MapPointsOfMap(1).size(), 3u);
  EXPECT_EQ(kfs[3]->parent(), kfs[2]);
  EXPECT_EQ(kfs[2]->parent(), nullptr);
  for (const MapPoint* p : atlas.MapPointsOfMap(1)) {
    for (const auto& [kf, index] : p->observations()) EXPECT_EQ(kf->session(), 1u);
  }
  EXPECT_EQ(atlas.next_point_id(), 9u);
}

TEST(Atlas, EachMapsFirstKeyFrameIsARootUntilAMergeGivesItAnOlderNeighbour) {
  testing::TempDir dir;
  Map map;
  {
    auto lock = map.WriteLock();
    KeyFrame* a = AddKeyFrameWithPoints(map, 0, 0.0, 20);
    KeyFrame* b = AddKeyFrameWithPoints(map, 1, 1.0, 0);
    ObservePointsOf(b, a, 20, 0);
    map.StartNewMap();
    KeyFrame* c = AddKeyFrameWithPoints(map, 2, 20.0, 20);
    KeyFrame* d = AddKeyFrameWithPoints(map, 3, 21.0, 0);
    ObservePointsOf(d, c, 20, 0);
    for (KeyFrame* kf : map.KeyFrames()) kf->UpdateConnections();
    EXPECT_EQ(b->parent(), a);
    EXPECT_EQ(d->parent(), c);
    // The new map's first keyframe sees only its younger child: taking it as parent closed a cycle.
    EXPECT_EQ(c->parent(), nullptr);
    map.MergeMapInto(1, 0);
    c->UpdateConnections();
    EXPECT_EQ(c->parent(), nullptr);  // still only its own descendants to choose from
  }
  // The map file of two maps loads with the same tree.
  const auto path = dir / "map.semslam";
  {
    auto lock = map.ReadLock();
    WriteMapFile(path, map);
  }
  Map loaded;
  {
    auto lock = loaded.WriteLock();
    ASSERT_NO_THROW(ReadMapFile(path, loaded));
    const auto kfs = loaded.KeyFrames();
    ASSERT_EQ(kfs.size(), 4u);
    EXPECT_EQ(kfs[1]->parent(), kfs[0]);
    EXPECT_EQ(kfs[2]->parent(), nullptr);
    EXPECT_EQ(kfs[3]->parent(), kfs[2]);
  }
  // Once the merged map's points are fused there, it hangs from the older map's keyframe.
  auto lock = map.WriteLock();
  const auto kfs = map.KeyFrames();
  ObservePointsOf(kfs[2], kfs[0], 20, 20);
  kfs[2]->UpdateConnections();
  EXPECT_EQ(kfs[2]->parent(), kfs[0]);
}

}  // namespace
}  // namespace semslam
