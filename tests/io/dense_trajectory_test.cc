// FillFrameGaps: one pose per frame for KITTI pose files, the gaps filled with the best pose known.

#include <algorithm>
#include <cmath>

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
  EXPECT_EQ(dense.Count(PoseSource::kInterpolated), 5u);  // 20..24
  EXPECT_EQ(dense.Count(PoseSource::kMotionModel), 2u);   // 28, 29
  for (size_t f = 10; f < 13; ++f) {
    EXPECT_EQ(dense.source[f - 10], PoseSource::kFirstPose);
    ExpectSamePose(dense.world_from_camera[f - 10], DrivePose(13), 1e-12, f);
  }
  // Steady motion through a turn: the bridge and the motion model give the true poses of the lost frames.
  for (const size_t f : {20, 21, 22, 23, 24}) {
    EXPECT_EQ(dense.source[f - 10], PoseSource::kInterpolated) << f;
    ExpectSamePose(dense.world_from_camera[f - 10], DrivePose(f), 1e-9, f);
  }
  for (const size_t f : {28, 29}) {
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
  // Frames 0 and 2 estimated (1 lost between): the step to frame 3 is half the motion from 0 to 2, and frame
  // 1, with no velocity known at either end, lies halfway along the motion from 0 to 2.
  const DenseTrajectory dense = FillFrameGaps(Estimated({0, 2}), 0, 4);
  EXPECT_EQ(dense.source[1], PoseSource::kInterpolated);
  ExpectSamePose(dense.world_from_camera[1], DrivePose(1), 1e-9, 1);
  EXPECT_EQ(dense.source[3], PoseSource::kMotionModel);
  ExpectSamePose(dense.world_from_camera[3], DrivePose(3), 1e-9, 3);
}

TEST(FillFrameGaps, ABridgeSpreadsTheDisagreementOfItsEnds) {
  // Tracking lost after frame 10 and found again at 31 with the world shifted 0.5 sideways (a
  // relocalization's error): the bridge leaves frame 10 on the true path and reaches 31's shifted one, each at
  // its end's velocity, the shift growing smoothly in between (3 s^2 - 2 s^3 of it, over the gap's share s, for
  // a drive that did not turn; here the turn bends it a little).
  const Eigen::Vector3d shift(0.5, 0, 0);
  std::vector<IndexedPose> estimated = Estimated({9, 10, 31, 32});
  for (size_t i = 2; i < 4; ++i) estimated[i].world_from_camera.translation += shift;
  const DenseTrajectory dense = FillFrameGaps(estimated, 9, 33);
  for (size_t f = 11; f <= 30; ++f) {
    EXPECT_EQ(dense.source[f - 9], PoseSource::kInterpolated) << f;
    const double s = static_cast<double>(f - 10) / 21.0;
    const Rigid3d expected(DrivePose(f).rotation,
                           DrivePose(f).translation + shift * (3 * s * s - 2 * s * s * s));
    ExpectSamePose(dense.world_from_camera[f - 9], expected, 0.03, f);
  }
  // Near its ends the bridge follows the ends' own motion: the first and last bridged frames are a step along it.
  EXPECT_LT((dense.world_from_camera[11 - 9].translation - DrivePose(11).translation).norm(), 0.01);
  EXPECT_LT((dense.world_from_camera[30 - 9].translation - DrivePose(30).translation - shift).norm(), 0.01);
}

TEST(FillFrameGaps, LongGapsAreBridgedAlongTheGeodesic) {
  // Straight ahead at 1 per frame, then the car stands: over a gap this long the ends' velocities are no
  // guide, and frame 6 lies halfway from frame 1 to frame 11; over a short one they shape the bridge.
  std::vector<IndexedPose> estimated;
  for (const auto& [frame, z] : std::vector<std::pair<size_t, double>>{{0, 0}, {1, 1}, {11, 2}, {12, 2}}) {
    estimated.push_back({frame, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, z))});
  }
  DenseTrajectoryOptions long_gap;
  long_gap.max_velocity_bridge_frames = 8;  // the gap holds 9 frames
  EXPECT_NEAR(FillFrameGaps(estimated, 0, 13, long_gap).world_from_camera[6].translation.z(), 1.5, 1e-12);
  // Defaults: the car slows steadily from 1 per frame (frames 0-1) to standing (frames 11-12). Carried from
  // frame 1 it is at 6 - 15/11 at frame 6, carried back from frame 11 at 7/11; halfway between.
  EXPECT_NEAR(FillFrameGaps(estimated, 0, 13).world_from_camera[6].translation.z(), 29.0 / 11.0, 1e-12);
}

TEST(FillFrameGaps, ASteadilyAcceleratingDriveIsBridgedExactly) {
  // Straight ahead, speeding up by 0.01 per frame per frame (the synthetic city's cars do), lost for 20 frames:
  // the constant velocities of the two ends, blended, fell 0.5 behind the car in the middle of the gap.
  const auto pose = [](size_t frame) {
    const double t = static_cast<double>(frame);
    return Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0.78 * t + 0.005 * t * t));
  };
  std::vector<IndexedPose> estimated;
  for (const size_t f : {8, 9, 30, 31}) estimated.push_back({f, pose(f)});
  const DenseTrajectory dense = FillFrameGaps(estimated, 8, 32);
  for (size_t f = 10; f < 30; ++f) {
    EXPECT_EQ(dense.source[f - 8], PoseSource::kInterpolated) << f;
    ExpectSamePose(dense.world_from_camera[f - 8], pose(f), 1e-9, f);
  }
}

TEST(FillFrameGaps, ATurnEasingOutInTheGapIsFollowed) {
  // 1 forward per frame, turning 0.1 rad per frame until frame 8, then the turn eases out (halving every 3
  // frames) while tracking is lost for frames 10..29, as at a corner's end of the synthetic city. The ends'
  // velocities, taken as changing linearly, turned 1.06 rad over the gap where the ends turn 0.38, and the
  // bridge strayed 1.43 at worst; it must reach its end along the turn that eased out.
  const auto pose = [](size_t frame) {
    Rigid3d p;
    for (size_t i = 0; i < frame; ++i) {
      const double rate = i < 8 ? 0.1 : 0.1 * std::exp2(-static_cast<double>(i - 8) / 3.0);
      p = p * Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(rate, Eigen::Vector3d::UnitY())),
                      Eigen::Vector3d(0, 0, 1));
    }
    return p;
  };
  std::vector<IndexedPose> estimated;
  for (const size_t f : {8, 9, 30, 31}) estimated.push_back({f, pose(f)});
  const DenseTrajectory dense = FillFrameGaps(estimated, 8, 32);
  double worst_translation = 0.0, worst_rotation = 0.0;
  for (size_t f = 10; f < 30; ++f) {
    EXPECT_EQ(dense.source[f - 8], PoseSource::kInterpolated) << f;
    const Rigid3d& bridged = dense.world_from_camera[f - 8];
    worst_translation = std::max(worst_translation, (bridged.translation - pose(f).translation).norm());
    worst_rotation = std::max(worst_rotation, bridged.rotation.angularDistance(pose(f).rotation));
  }
  EXPECT_LT(worst_translation, 0.2);
  EXPECT_LT(worst_rotation, 0.1);  // rad; the easing is steeper than the bump's shape
}

TEST(FillFrameGaps, MotionIsCarriedInTimeOverDroppedFrames) {
  // The camera dropped true frames 10..29 (2 s at 10 Hz): recorded frame r is true frame r, then r + 20.
  // Tracking is lost for recorded 10..14 and after 16; the recorded frames' times say where the car was.
  auto true_frame = [](size_t recorded) { return recorded < 10 ? recorded : recorded + 20; };
  std::vector<double> times;
  for (size_t r = 0; r < 20; ++r) times.push_back(0.1 * static_cast<double>(true_frame(r)));
  std::vector<IndexedPose> estimated;
  for (const size_t r : {8, 9, 15, 16}) estimated.push_back({r, DrivePose(true_frame(r))});
  const DenseTrajectory dense = FillFrameGaps(estimated, 0, 20, {}, times);
  for (size_t r = 10; r < 15; ++r) {
    EXPECT_EQ(dense.source[r], PoseSource::kInterpolated) << r;
    ExpectSamePose(dense.world_from_camera[r], DrivePose(true_frame(r)), 1e-9, r);
  }
  for (size_t r = 17; r < 20; ++r) {
    EXPECT_EQ(dense.source[r], PoseSource::kMotionModel) << r;
    ExpectSamePose(dense.world_from_camera[r], DrivePose(true_frame(r)), 1e-9, r);
  }
  EXPECT_THROW(FillFrameGaps(estimated, 0, 20, {}, std::vector<double>(19, 0.0)), InvalidArgument);
  times[12] = times[11];
  EXPECT_THROW(FillFrameGaps(estimated, 0, 20, {}, times), InvalidArgument);
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
