// MatchesInCameraFrames: the matches a loop's Sim(3) is estimated on, each point in its keyframe's camera.

#include <gtest/gtest.h>

#include "map_test_frames.h"
#include "semslam/map/keyframe_matches.h"
#include "semslam/map/map.h"

namespace semslam {
namespace {

TEST(MatchesInCameraFrames, KeepsUsableMatchesInEachCamerasFrame) {
  Map map;
  auto lock = map.WriteLock();
  KeyFrame* kf1 = map.AddKeyFrame(MakeFrame(0, 20, /*stereo=*/false, {0, 0, 0}));
  KeyFrame* kf2 = map.AddKeyFrame(MakeFrame(1, 20, /*stereo=*/false, {1, 0, 2}));
  // Keyframe 1 holds points in slots 0-5; keyframe 2 observes their matches in slots 10-15.
  std::vector<MapPoint*> own, theirs;
  for (int i = 0; i < 6; ++i) {
    MapPoint* p = map.AddMapPoint(Eigen::Vector3d(i, 0.5, 10.0), kf1);
    p->AddObservation(kf1, i);
    kf1->SetMapPoint(i, p);
    own.push_back(p);
    MapPoint* q = map.AddMapPoint(Eigen::Vector3d(i, -0.5, 12.0), kf2);
    q->AddObservation(kf2, 10 + i);
    kf2->SetMapPoint(10 + i, q);
    theirs.push_back(q);
  }
  MapPoint* unobserved = map.AddMapPoint(Eigen::Vector3d(0, 0, 5), kf2);  // in no keyframe 2 slot
  std::vector<MapPoint*> matches12(kf1->num_features(), nullptr);
  for (int i = 0; i < 5; ++i) matches12[static_cast<size_t>(i)] = theirs[static_cast<size_t>(i)];
  matches12[4] = unobserved;
  theirs[2]->SetBad();
  own[3]->SetBad();
  matches12[7] = theirs[5];  // keyframe 1 holds no point in slot 7

  const std::vector<KeyFramePointMatch> usable = MatchesInCameraFrames(*kf1, *kf2, matches12);
  ASSERT_EQ(usable.size(), 2u) << "slots 0 and 1: 2 and 3 are bad, 4 unobserved, 5 unmatched, 7 empty";
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_EQ(usable[k].slot1, k);
    EXPECT_EQ(usable[k].slot2, 10 + k);
    EXPECT_TRUE(usable[k].point1.isApprox(Eigen::Vector3d(static_cast<double>(k), 0.5, 10.0)));
    EXPECT_TRUE(usable[k].point2.isApprox(Eigen::Vector3d(static_cast<double>(k) - 1.0, -0.5, 10.0)))
        << "keyframe 2's camera stands at (1, 0, 2)";
  }

  // A matches vector shorter than the keyframe's keypoints is read as far as it goes.
  matches12.resize(1);
  EXPECT_EQ(MatchesInCameraFrames(*kf1, *kf2, matches12).size(), 1u);
}

}  // namespace
}  // namespace semslam
