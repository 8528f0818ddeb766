#include <gtest/gtest.h>

#include "semslam/map/map.h"
#include "semslam/tracking/tracker.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

Frame FrameAt(std::uint64_t id, const Eigen::Vector3d& center) {
  Frame frame(id, 0.1 * static_cast<double>(id),
              MakeFrameData(KittiCamera(), std::nullopt, FeatureSet{}, {}, {}));
  frame.SetPose(
      Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * static_cast<double>(id), Eigen::Vector3d::UnitY())),
              -center));
  return frame;
}

double Distance(const Rigid3d& a, const Rigid3d& b) {
  return (a.translation - b.translation).norm() + a.rotation.angularDistance(b.rotation);
}

TEST(FrameRecord, FollowsItsKeyFrameThroughCorrectionsAndCulling) {
  Map map;
  auto lock = map.WriteLock();
  KeyFrame* kf0 = map.AddKeyFrame(FrameAt(0, {0, 0, 0}));
  KeyFrame* kf1 = map.AddKeyFrame(FrameAt(3, {0, 0, 3}));
  kf1->ChangeParent(kf0);
  const Rigid3d camera_from_world = FrameAt(5, {0.2, 0, 5}).camera_from_world();
  FrameRecord record;
  record.frame_id = 5;
  record.reference = kf1;
  record.camera_from_reference = camera_from_world * kf1->world_from_camera();
  ASSERT_TRUE(CurrentCameraFromWorld(record).has_value());
  EXPECT_LT(Distance(*CurrentCameraFromWorld(record), camera_from_world), 1e-12);

  // A loop correction moves the keyframe 4 m: the frame moves with it.
  const Rigid3d shift(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())), {4, 0, 0});
  kf1->SetPose(kf1->camera_from_world() * shift);
  const Rigid3d moved = camera_from_world * shift;
  EXPECT_LT(Distance(*CurrentCameraFromWorld(record), moved), 1e-12);
  EXPECT_GT(Distance(moved, camera_from_world), 1.0);

  // Culled, the keyframe hands the frame to its parent with the same pose.
  kf1->SetBad();
  ASSERT_TRUE(kf1->is_bad());
  ASSERT_TRUE(CurrentCameraFromWorld(record).has_value());
  EXPECT_LT(Distance(*CurrentCameraFromWorld(record), moved), 1e-9);

  // Untracked frames have no pose.
  record.reference = nullptr;
  EXPECT_FALSE(CurrentCameraFromWorld(record).has_value());
}

}  // namespace
}  // namespace semslam
