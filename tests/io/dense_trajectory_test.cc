// FillFrameGaps: one pose per frame for KITTI pose files, the gaps filled with the best pose known.

#include <gtest/gtest.h>

#include "semslam/core/error.h"
#include "semslam/io/trajectory_io.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

// A camera driving forward 1 unit per frame while turning 0.02 rad per frame about its y axis (down).
Rigid3d DrivePose(size_t frame) {
  const Rigid3d step(Eigen::Quaterniond(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY())),
                     Eigen::Vector3d(0, 0, 1));
  Rigid3d pose;
  for (size_t i = 0; i < frame; ++i) pose = pose * step;
  return pose;
}

std::vector<IndexedPose> Estimated(const std::vector<size_t>& frames) {
  std::vector<IndexedPose> poses;
  for (const size_t f : frames) poses.push_back({f, DrivePose(f)});
  return poses;
}

void ExpectSamePose(const Rigid3d& a, const Rigid3d& b, double tolerance, size_t frame) {
  EXPECT_LE((a.translation - b.translation).norm(), tolerance) << "frame " << frame;
  EXPECT_LE(a.rotation.angularDistance(b.rotation), tolerance) << "frame " << frame;
}

TEST(FillFrameGaps, EveryFrameGetsALine) {
  // Frames 10..29; tracking starts at 13 (a monocular initialization), is lost for 20..24 and after 27.
  const DenseTrajectory dense =
      FillFrameGaps(Estimated({13, 14, 15, 16, 17, 18, 19, 25, 26, 27}), 10, 30);
  ASSERT_EQ(dense.world_from_camera.size(), 20u);
  ASSERT_EQ(dense.source.size(), 20u);
  EXPECT_EQ(dense.first_frame, 10u);
  EXPECT_EQ(dense.Count(PoseSource::kEstimated), 10u);
  EXPECT_EQ(dense.Count(PoseSource::kFirstPose), 3u);
  EXPECT_EQ(dense.Count(PoseSource::kMotionModel), 7u);  // 20..24 and 28, 29
  for (size_t f = 10; f < 13; ++f) {
    EXPECT_EQ(dense.source[f - 10], PoseSource::kFirstPose);
    ExpectSamePose(dense.world_from_camera[f - 10], DrivePose(13), 1e-12, f);
  }
  // Constant motion: the motion model predicts the true poses of the lost frames.
  for (const size_t f : {20, 21, 22, 23, 24, 28, 29}) {
    EXPECT_EQ(dense.source[f - 10], PoseSource::kMotionModel) << f;
    ExpectSamePose(dense.world_from_camera[f - 10], DrivePose(f), 1e-9, f);
  }
  for (const size_t f : {13, 19, 25, 27}) {
    EXPECT_EQ(dense.source[f - 10], PoseSource::kEstimated);
    ExpectSamePose(dense.world_from_camera[f - 10], DrivePose(f), 1e-12, f);
  }
}

TEST(FillFrameGaps, LongGapsHoldTheLastPrediction) {
  DenseTrajectoryOptions options;
  options.max_predicted_frames = 3;
  const DenseTrajectory dense = FillFrameGaps(Estimated({0, 1}), 0, 8, options);
  for (size_t f = 2; f <= 4; ++f) {
    EXPECT_EQ(dense.source[f], PoseSource::kMotionModel);
    ExpectSamePose(dense.world_from_camera[f], DrivePose(f), 1e-9, f);
  }
  for (size_t f = 5; f < 8; ++f) {
    EXPECT_EQ(dense.source[f], PoseSource::kHeld);
    ExpectSamePose(dense.world_from_camera[f], DrivePose(4), 1e-9, f);
  }
}

TEST(FillFrameGaps, VelocityOverAGapIsPerFrame) {
  // Frames 0 and 2 estimated (1 lost between): the step to frame 3 is half the motion from 0 to 2.
  const DenseTrajectory dense = FillFrameGaps(Estimated({0, 2}), 0, 4);
  EXPECT_EQ(dense.source[1], PoseSource::kHeld);  // no velocity known yet: frame 0's pose
  ExpectSamePose(dense.world_from_camera[1], DrivePose(0), 1e-12, 1);
  EXPECT_EQ(dense.source[3], PoseSource::kMotionModel);
  ExpectSamePose(dense.world_from_camera[3], DrivePose(3), 1e-9, 3);
}

TEST(FillFrameGaps, NothingEstimatedGivesIdentitiesAndOutsidePosesAreIgnored) {
  const DenseTrajectory none = FillFrameGaps({}, 5, 8);
  ASSERT_EQ(none.world_from_camera.size(), 3u);
  EXPECT_EQ(none.Count(PoseSource::kNone), 3u);
  ExpectSamePose(none.world_from_camera[0], Rigid3d(), 0.0, 5);

  const DenseTrajectory outside = FillFrameGaps(Estimated({1, 2, 9}), 3, 6);
  EXPECT_EQ(outside.Count(PoseSource::kNone), 3u);
  EXPECT_TRUE(FillFrameGaps(Estimated({1}), 4, 4).world_from_camera.empty());

  EXPECT_THROW(FillFrameGaps(Estimated({3, 2}), 0, 5), InvalidArgument);
  EXPECT_THROW(FillFrameGaps({}, 5, 4), InvalidArgument);
}

TEST(KittiPoses, CountWithoutParsing) {
  testing::TempDir dir;
  testing::WriteText(dir / "p.txt", "# comment\n1 0 0 0 0 1 0 0 0 0 1 0\n\n1 0 0 1 0 1 0 0 0 0 1 0\n");
  EXPECT_EQ(CountKittiPoses(dir / "p.txt"), 2u);
}

}  // namespace
}  // namespace semslam
