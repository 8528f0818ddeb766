#include <gtest/gtest.h>

#include "semslam/geometry/sim3.h"
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

// Two keyframes (kf1 the child of kf0) and frame 5 recorded relative to kf1.
class FrameRecordTest : public ::testing::Test {
 protected:
  FrameRecordTest() : lock(map.WriteLock()) {
    kf0 = map.AddKeyFrame(FrameAt(0, {0, 0, 0}));
    kf1 = map.AddKeyFrame(FrameAt(3, {0, 0, 3}));
    kf1->ChangeParent(kf0);
    record.frame_id = 5;
    record.reference = kf1;
    record.camera_from_reference = camera_from_world * kf1->world_from_camera();
    record.reference_scale = kf1->scale_correction();
  }

  Map map;
  std::unique_lock<std::shared_mutex> lock;
  KeyFrame* kf0 = nullptr;
  KeyFrame* kf1 = nullptr;
  const Rigid3d camera_from_world = FrameAt(5, {0.2, 0, 5}).camera_from_world();
  FrameRecord record;
};

TEST_F(FrameRecordTest, FollowsItsKeyFrameThroughCorrectionsAndCulling) {
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

// camera_from_world after the whole map is moved by new_from_old (a monocular merge or loop correction):
// the pose keeps its rotation, and its translation is in the new units.
Rigid3d Moved(const Rigid3d& camera_from_world, const Sim3d& new_from_old) {
  const Sim3d moved = Sim3d(camera_from_world) * new_from_old.Inverse();
  return Rigid3d(moved.rotation, moved.translation / moved.scale);
}

void MoveKeyFrame(KeyFrame* kf, const Sim3d& new_from_old) {
  kf->SetPose(Moved(kf->camera_from_world(), new_from_old));
  kf->CorrectScale(new_from_old.scale);
}

TEST_F(FrameRecordTest, StretchesWithItsKeyFrameWhenTheMapIsRescaled) {
  const double offset = (camera_from_world.Inverse().translation - kf1->center()).norm();

  // A merge moves the map 1.8 times larger: the frame is then 1.8 times as far from its keyframe.
  const Sim3d merge(1.8, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())), {5, 0, -2});
  MoveKeyFrame(kf0, merge);
  MoveKeyFrame(kf1, merge);
  Rigid3d expected = Moved(camera_from_world, merge);
  ASSERT_TRUE(CurrentCameraFromWorld(record).has_value());
  EXPECT_LT(Distance(*CurrentCameraFromWorld(record), expected), 1e-9);
  EXPECT_NEAR((expected.Inverse().translation - kf1->center()).norm(), 1.8 * offset, 1e-9);
  EXPECT_GT(offset, 1.0);

  // Culled, the keyframe hands the frame to its parent, and a later correction of the parent stretches both
  // offsets (frame to culled keyframe, culled keyframe to parent).
  kf1->SetBad();
  ASSERT_TRUE(kf1->is_bad());
  const Sim3d loop(0.7, Eigen::Quaterniond(Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitY())), {1, 0, 4});
  MoveKeyFrame(kf0, loop);
  MoveKeyFrame(kf1, loop);  // a culled keyframe follows its parent: correcting it too changes nothing
  expected = Moved(expected, loop);
  ASSERT_TRUE(CurrentCameraFromWorld(record).has_value());
  EXPECT_LT(Distance(*CurrentCameraFromWorld(record), expected), 1e-9);
  EXPECT_NEAR(kf1->scale_correction(), 1.8 * 0.7, 1e-12);
}

}  // namespace
}  // namespace semslam
