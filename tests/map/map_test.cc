#include "semslam/map/map.h"

#include <gtest/gtest.h>

#include <fstream>
#include <random>

#include "semslam/core/error.h"
#include "semslam/map/map_file.h"
#include "map_test_frames.h"
#include "support/test_support.h"

namespace semslam {
namespace {

// Two keyframes sharing `shared` points (keypoint i <-> keypoint i), plus a third seeing the first `third` of
// them.
struct SmallMap {
  Map map;
  KeyFrame* kf0 = nullptr;
  KeyFrame* kf1 = nullptr;
  KeyFrame* kf2 = nullptr;
  std::vector<MapPoint*> points;

  explicit SmallMap(bool stereo = false, int shared = 30, int third = 20) {
    auto lock = map.WriteLock();
    kf0 = map.AddKeyFrame(MakeFrame(0, 200, stereo, {0, 0, 0}));
    kf1 = map.AddKeyFrame(MakeFrame(1, 200, stereo, {0, 0, 1}));
    kf2 = map.AddKeyFrame(MakeFrame(2, 200, stereo, {0, 0, 2}));
    for (int i = 0; i < shared; ++i) {
      MapPoint* p = map.AddMapPoint(Eigen::Vector3d(0.1 * i, 0.05 * i, 10.0 + i), kf0);
      p->AddObservation(kf0, i);
      kf0->SetMapPoint(i, p);
      p->AddObservation(kf1, i);
      kf1->SetMapPoint(i, p);
      if (i < third) {
        p->AddObservation(kf2, i);
        kf2->SetMapPoint(i, p);
      }
      p->UpdateDescriptor();
      p->UpdateNormalAndDepth();
      points.push_back(p);
    }
    for (KeyFrame* kf : {kf0, kf1, kf2}) kf->UpdateConnections();
  }
};

TEST(MapPoint, ObservationsAndBadness) {
  SmallMap m;
  MapPoint* p = m.points[0];
  EXPECT_EQ(p->num_observations(), 3);
  EXPECT_EQ(p->IndexIn(m.kf1), 0);
  EXPECT_EQ(p->IndexIn(nullptr), -1);
  // Fewer than three camera observations left: the point turns bad and leaves its keyframes.
  p->EraseObservation(m.kf2);
  EXPECT_TRUE(p->is_bad());
  EXPECT_EQ(p->num_observations(), 0);
  EXPECT_EQ(m.kf0->map_point(0), nullptr);
  EXPECT_EQ(m.kf1->map_point(0), nullptr);
  // A stereo observation counts twice: two stereo keyframes keep a point alive after a third leaves.
  SmallMap s(/*stereo=*/true);
  MapPoint* q = s.points[1];  // keypoint 1 has depth in every keyframe
  q->EraseObservation(s.kf2);
  EXPECT_FALSE(q->is_bad());
  EXPECT_EQ(q->num_observations(), 4);
}

TEST(MapPoint, StereoObservationCountsTwice) {
  SmallMap m(/*stereo=*/true);
  // Keypoint 1 has stereo depth (i % 3 != 0), keypoint 0 has none.
  EXPECT_EQ(m.points[0]->num_observations(), 3);
  EXPECT_EQ(m.points[1]->num_observations(), 6);
}

TEST(MapPoint, ReplaceWithMovesObservationsAndMultipliesLabels) {
  SmallMap m;
  MapPoint* a = m.points[0];
  MapPoint* b = m.points[25];  // seen by kf0 and kf1 only
  ClassLogProbs building{}, building2{};
  building.fill(-2.0f);
  building[2] = -0.5f;
  building2.fill(-2.0f);
  building2[2] = -0.25f;
  a->labels().Fuse(building);
  a->labels().Fuse(building);
  b->labels().Fuse(building2);
  const float a_building = a->labels().Probabilities()[2];
  a->ReplaceWith(b);
  EXPECT_TRUE(a->is_bad());
  EXPECT_EQ(a->Resolve(), b);
  // kf2 saw a at keypoint 0 and not b: it now sees b there. kf0/kf1 saw both: b keeps its own slots.
  EXPECT_EQ(m.kf2->map_point(0), b);
  EXPECT_EQ(b->IndexIn(m.kf2), 0);
  EXPECT_EQ(m.kf0->map_point(0), nullptr);
  // Posteriors multiply: three observations favouring building, stronger than a's two.
  EXPECT_EQ(b->labels().NumObservations(), 3);
  EXPECT_EQ(b->labels().Label(), 2);
  EXPECT_GT(b->labels().Probabilities()[2], a_building);
}

TEST(MapPoint, ObservationOfASegmentedKeyframeFusesItsLabel) {
  SmallMap m;
  std::vector<float> rows(m.kf2->num_features() * kNumClasses, 0.0f);  // all "no observation"...
  for (int c = 0; c < kNumClasses; ++c)
    rows[25 * kNumClasses + static_cast<size_t>(c)] = c == 13 ? -0.05f : -5.0f;
  m.kf2->keypoint_labels.Assign(rows);  // ...but keypoint 25: car
  ClassLogProbs probe;
  ASSERT_TRUE(m.kf2->keypoint_labels.Get(25, &probe));
  EXPECT_NEAR(probe[13], -0.0625f, 1e-6);  // quantized to 1/16 nat
  EXPECT_NEAR(probe[0], -5.0f, 1e-6);
  EXPECT_FALSE(m.kf2->keypoint_labels.Get(24, &probe));

  MapPoint* p = m.points[25];  // seen by kf0 and kf1 only
  EXPECT_FALSE(p->labels().HasObservations());
  p->AddObservation(m.kf2, 25);
  EXPECT_EQ(p->labels().NumObservations(), 1);
  EXPECT_EQ(p->labels().Label(), 13);
  EXPECT_TRUE(p->IsDynamic());
  MapPoint* q = m.points[24];
  q->AddObservation(m.kf2, 24);  // no observation at that keypoint
  EXPECT_FALSE(q->labels().HasObservations());
  EXPECT_FALSE(q->IsDynamic());
}

TEST(KeyFrame, CovisibilityAndSpanningTree) {
  SmallMap m;
  EXPECT_EQ(m.kf0->ConnectionWeight(m.kf1), 30);
  EXPECT_EQ(m.kf1->ConnectionWeight(m.kf2), 20);
  EXPECT_EQ(m.kf2->ConnectionWeight(m.kf0), 20);
  ASSERT_FALSE(m.kf1->Covisibles().empty());
  EXPECT_EQ(m.kf1->Covisibles().front(), m.kf0);  // strongest first
  EXPECT_EQ(m.kf1->parent(), m.kf0);
  EXPECT_EQ(m.kf2->parent(), m.kf0);  // older keyframes preferred, then by weight
  EXPECT_EQ(m.kf0->parent(), nullptr);
  EXPECT_EQ(m.kf1->CovisiblesWithWeightAtLeast(25).size(), 1u);
}

TEST(KeyFrame, SetBadReparentsChildrenAndKeepsRelativePose) {
  SmallMap m;
  // Make kf2 a child of kf1.
  m.kf2->ChangeParent(m.kf1);
  m.kf1->SetBad();
  EXPECT_TRUE(m.kf1->is_bad());
  EXPECT_EQ(m.kf2->parent(), m.kf0);
  EXPECT_EQ(m.kf0->ConnectionWeight(m.kf1), 0);
  // camera_from_parent recovers kf1's pose from its parent's.
  const Rigid3d recovered = m.kf1->camera_from_parent() * m.kf0->camera_from_world();
  EXPECT_LT((recovered.translation - m.kf1->camera_from_world().translation).norm(), 1e-12);
  // The first keyframe is never erased; a protected one only when released.
  m.kf0->SetBad();
  EXPECT_FALSE(m.kf0->is_bad());
  m.kf2->SetNotErase();
  m.kf2->SetBad();
  EXPECT_FALSE(m.kf2->is_bad());
  m.kf2->SetErase();
  EXPECT_TRUE(m.kf2->is_bad());
}

TEST(Map, ClearMarksEverythingBad) {
  SmallMap m;
  auto lock = m.map.WriteLock();
  const int before = m.map.big_change_index();
  m.map.Clear();
  EXPECT_EQ(m.map.NumKeyFrames(), 0u);
  EXPECT_EQ(m.map.NumMapPoints(), 0u);
  EXPECT_TRUE(m.kf1->is_bad());
  EXPECT_TRUE(m.points[0]->is_bad());
  EXPECT_GT(m.map.big_change_index(), before);
}

TEST(MapFile, RoundTripIsExact) {
  testing::TempDir dir;
  SmallMap m(/*stereo=*/true);
  ClassLogProbs vegetation;
  vegetation.fill(-3.0f);
  vegetation[8] = -0.01f;
  for (int k = 0; k < 4; ++k) m.points[3]->labels().Fuse(vegetation);
  std::vector<float> rows(m.kf2->num_features() * kNumClasses, 0.0f);
  for (int c = 0; c < kNumClasses; ++c)
    rows[5 * kNumClasses + static_cast<size_t>(c)] = c == 13 ? -0.1f : -4.0f;
  m.kf2->keypoint_labels.Assign(rows);
  m.kf1->gps_enu = Eigen::Vector3d(1.5, -2.5, 0.25);
  m.kf1->gps_sigma_m = 1.0;
  m.kf1->AddLoopEdge(m.kf2);
  m.kf2->AddLoopEdge(m.kf1);
  MapFileContents extra;
  extra.extra_sections["geo.alignment"] = R"({"scale": 2.0})";
  const auto path = dir / "map.semslam";
  {
    auto lock = m.map.ReadLock();
    WriteMapFile(path, m.map, extra);
  }

  Map loaded;
  MapFileContents contents;
  {
    auto lock = loaded.WriteLock();
    contents = ReadMapFile(path, loaded);
  }
  EXPECT_EQ(contents.extra_sections, extra.extra_sections);
  ASSERT_EQ(loaded.NumKeyFrames(), 3u);
  ASSERT_EQ(loaded.NumMapPoints(), m.map.NumMapPoints());
  const auto kfs = loaded.KeyFrames();
  const std::vector<KeyFrame*> original = {m.kf0, m.kf1, m.kf2};
  for (size_t k = 0; k < 3; ++k) {
    const KeyFrame* a = original[k];
    const KeyFrame* b = kfs[k];
    EXPECT_EQ(a->id(), b->id());
    EXPECT_EQ(a->frame_id(), b->frame_id());
    EXPECT_EQ(a->timestamp(), b->timestamp());
    EXPECT_EQ(a->camera_from_world().translation, b->camera_from_world().translation);
    EXPECT_EQ(a->camera_from_world().rotation.coeffs(), b->camera_from_world().rotation.coeffs());
    ASSERT_EQ(a->num_features(), b->num_features());
    for (size_t i = 0; i < a->num_features(); ++i) {
      EXPECT_EQ(a->features().keypoints[i].pixel, b->features().keypoints[i].pixel);
      EXPECT_EQ(a->features().keypoints[i].level, b->features().keypoints[i].level);
      EXPECT_EQ(a->features().keypoints[i].angle_deg, b->features().keypoints[i].angle_deg);
      EXPECT_EQ(a->features().descriptors[i], b->features().descriptors[i]);
      EXPECT_EQ(a->data().depth[i], b->data().depth[i]);
      EXPECT_EQ(a->data().right_u[i], b->data().right_u[i]);
    }
    EXPECT_EQ(a->parent() ? a->parent()->id() : 99u, b->parent() ? b->parent()->id() : 99u);
    EXPECT_EQ(a->loop_edges().size(), b->loop_edges().size());
    ASSERT_TRUE(b->data().stereo.has_value());
    EXPECT_EQ(b->data().stereo->baseline, 0.54);
  }
  EXPECT_EQ(kfs[2]->keypoint_labels.quantized(), m.kf2->keypoint_labels.quantized());
  EXPECT_EQ(kfs[2]->keypoint_labels.labeled(), m.kf2->keypoint_labels.labeled());
  EXPECT_EQ(loaded.MapPoints()[3]->labels().Label(), 8);
  ASSERT_TRUE(kfs[1]->gps_enu.has_value());
  EXPECT_EQ(*kfs[1]->gps_enu, *m.kf1->gps_enu);
  const auto points = loaded.MapPoints();
  for (size_t i = 0; i < points.size(); ++i) {
    const MapPoint* a = m.points[i];
    const MapPoint* b = points[i];
    EXPECT_EQ(a->id(), b->id());
    EXPECT_EQ(a->position(), b->position());
    EXPECT_EQ(a->num_observations(), b->num_observations());
    EXPECT_EQ(a->descriptor(), b->descriptor());
    EXPECT_TRUE(a->labels() == b->labels());
    for (const auto& [kf, index] : b->observations()) EXPECT_EQ(kf->map_point(index), b);
  }
  EXPECT_EQ(kfs[0]->ConnectionWeight(kfs[1]), 30);

  // Writing the loaded map again gives the same bytes.
  const auto again = dir / "again.semslam";
  {
    auto lock = loaded.ReadLock();
    WriteMapFile(again, loaded, contents);
  }
  std::ifstream f1(path, std::ios::binary), f2(again, std::ios::binary);
  const std::string b1((std::istreambuf_iterator<char>(f1)), {}),
      b2((std::istreambuf_iterator<char>(f2)), {});
  EXPECT_EQ(b1, b2);
}

TEST(MapFile, CorruptTruncatedAndForeignFilesAreRejected) {
  testing::TempDir dir;
  SmallMap m;
  const auto path = dir / "map.semslam";
  {
    auto lock = m.map.ReadLock();
    WriteMapFile(path, m.map);
  }
  std::string bytes;
  {
    std::ifstream f(path, std::ios::binary);
    bytes.assign((std::istreambuf_iterator<char>(f)), {});
  }
  auto expect_rejected = [&](const std::string& content, const std::string& name) {
    const auto bad = dir / name;
    std::ofstream(bad, std::ios::binary) << content;
    Map map;
    auto lock = map.WriteLock();
    try {
      ReadMapFile(bad, map);
      ADD_FAILURE() << name << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  std::string flipped = bytes;
  flipped[flipped.size() / 2] ^= 0x5a;
  expect_rejected(flipped, "flipped.semslam");
  expect_rejected(bytes.substr(0, bytes.size() - 100), "truncated.semslam");
  std::string foreign = bytes;
  foreign[0] = 'X';
  expect_rejected(foreign, "foreign.semslam");
  expect_rejected("", "empty.semslam");

  Map map;
  auto lock = map.WriteLock();
  EXPECT_THROW(ReadMapFile(dir / "missing.semslam", map), InputError);
}

}  // namespace
}  // namespace semslam
