// KeyFrameGraphDistance: the odometry between two keyframes along the links of the essential graph.

#include <gtest/gtest.h>

#include <cmath>

#include "map_test_frames.h"
#include "semslam/map/keyframe_graph.h"
#include "semslam/map/map.h"

namespace semslam {
namespace {

TEST(KeyFrameGraphDistance, FollowsTheTreeAndTakesLoopsAsShortcuts) {
  // A drive round three sides of a 10 m square: 0 -> 1 -> 2 -> 3, each the parent of the next.
  Map map;
  auto lock = map.WriteLock();
  const Eigen::Vector3d corners[] = {{0, 0, 0}, {0, 0, 10}, {10, 0, 10}, {10, 0, 0}};
  std::vector<KeyFrame*> kfs;
  for (std::uint64_t i = 0; i < 4; ++i) {
    kfs.push_back(map.AddKeyFrame(MakeFrame(i, 20, /*stereo=*/false, corners[i])));
    if (i > 0) kfs[i]->ChangeParent(kfs[i - 1]);
  }
  EXPECT_NEAR(KeyFrameGraphDistance(*kfs[0], *kfs[3], 100), 30.0, 1e-9);
  EXPECT_NEAR(KeyFrameGraphDistance(*kfs[3], *kfs[0], 100), 30.0, 1e-9) << "the links go both ways";
  EXPECT_NEAR(KeyFrameGraphDistance(*kfs[2], *kfs[2], 100), 0.0, 1e-12);

  // A loop between the ends makes the fourth side the shortest chain from 0 to 3 and from 1 to 3.
  kfs[0]->AddLoopEdge(kfs[3]);
  kfs[3]->AddLoopEdge(kfs[0]);
  EXPECT_NEAR(KeyFrameGraphDistance(*kfs[0], *kfs[3], 100), 10.0, 1e-9);
  EXPECT_NEAR(KeyFrameGraphDistance(*kfs[1], *kfs[3], 100), 20.0, 1e-9);

  // Another map's keyframe is not reachable.
  map.StartNewMap();
  KeyFrame* other = map.AddKeyFrame(MakeFrame(4, 20, /*stereo=*/false, {0, 0, 1}));
  EXPECT_TRUE(std::isinf(KeyFrameGraphDistance(*kfs[0], *other, 100)));
}

}  // namespace
}  // namespace semslam
