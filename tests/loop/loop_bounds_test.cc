// The bounds a loop within one map must keep against the odometry between its two ends.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/loop/loop_closer.h"

namespace semslam {
namespace {

Eigen::Quaterniond Yaw(double degrees) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitY()));
}

TEST(MeasureCorrection, GivesTheMoveOfTheCameraCentreAndTheTurnWhateverTheScale) {
  const Rigid3d before(Yaw(10.0), Eigen::Vector3d(1, 2, 3));
  const Eigen::Vector3d centre = before.Inverse().translation;
  // A Sim(3) camera_from_world whose camera stands 4 m along x from the keyframe, turned 80.5 degrees.
  const Rigid3d moved = Rigid3d(Yaw(90.5), Eigen::Vector3d::Zero()) *
                        Rigid3d(Eigen::Quaterniond::Identity(), -(centre + Eigen::Vector3d(4, 0, 0)));
  const double scale = 0.5;
  const LoopCorrectionSize size = MeasureCorrection(before, Sim3d(scale, moved.rotation, scale * moved.translation));
  EXPECT_NEAR(size.metres, 4.0, 1e-9);
  EXPECT_NEAR(size.degrees, 80.5, 1e-9);
  const LoopCorrectionSize none = MeasureCorrection(before, Sim3d(before));
  EXPECT_NEAR(none.metres, 0.0, 1e-9);
  EXPECT_NEAR(none.degrees, 0.0, 1e-6);
}

// The black-out drive (synthetic stereo, 2 s black): after 366.6 m of graph odometry the query keyframe matched a
// corner seen from the other street. The correction would have moved it 12.3 m, inside the 14.0 m length bound,
// and turned it 90 degrees; the true loops of the drive moved it 0.3-0.5 m and turned it under a degree. Look-alike
// blocks elsewhere (133 m away, turned 0.1 degrees) are the length bound's.
TEST(LoopBounds, StereoRefusesTheCornerAliasByItsTurnAndKeepsTheTrueLoop) {
  LoopCloserOptions options;
  options.fix_scale = true;
  EXPECT_NEAR(options.MaxStereoCorrectionM(366.6), 14.0, 0.01);
  EXPECT_NEAR(options.MaxRotationDeg(366.6), 12.33, 0.01);
  EXPECT_FALSE(options.AllowsCorrection({12.3, 90.0}, 366.6, 0.0));
  EXPECT_TRUE(options.AllowsCorrection({0.3, 0.2}, 361.4, 0.0));
  EXPECT_FALSE(options.AllowsCorrection({133.1, 0.1}, 321.4, 0.0));
  EXPECT_TRUE(options.AllowsCorrection({2.0, 4.9}, 0.0, 0.0))
      << "a short loop may still turn a keyframe by its noise";
  EXPECT_FALSE(options.AllowsCorrection({2.0, 5.1}, 0.0, 0.0));
  EXPECT_TRUE(options.AllowsCorrection({2.0, 40.0}, 2000.0, 0.0)) << "heading drift grows with the path";
}

// Monocular loops logged in map units (a map's unit starts as its first keyframe's median scene depth). KITTI
// 00's revisit, whose map's scale had drifted to 2.116 over the drive, moved its keyframe 8.35 after 78.6 of
// odometry; a true loop of town 2468's route 2, 0.015 after 18.1. In the merged town the odometry between two
// drives is the merge's link: their loops moved the keyframe up to 0.15 after 2.5. Look-alike blocks 101 m
// from the place (town 9999 route 4, frames 529 and 42) and in the merged town 2468 would have moved it 5.64
// after 22.8 and 5.50 after 14.7, turning it only 1.7 and 0.2 degrees.
TEST(LoopBounds, MonocularRefusesALookAlikeByItsMoveAndAllowsForTheScaleDrift) {
  LoopCloserOptions options;
  options.fix_scale = false;
  EXPECT_TRUE(options.AllowsCorrection({8.353, 1.1, 2.116}, 78.569, 1.11));
  EXPECT_TRUE(options.AllowsCorrection({0.015, 0.5, 0.989}, 18.144, 0.84));
  EXPECT_TRUE(options.AllowsCorrection({0.15, 0.2, 1.049}, 2.46, 1.26));
  EXPECT_TRUE(options.AllowsCorrection({0.11, 0.1, 0.987}, 1.23, 0.98));
  EXPECT_FALSE(options.AllowsCorrection({5.636, 1.7, 0.962}, 22.840, 1.11));
  EXPECT_FALSE(options.AllowsCorrection({5.50, 0.2, 1.054}, 14.73, 1.15));
  EXPECT_FALSE(options.AllowsCorrection({8.353, 1.1, 1.0}, 78.569, 1.11))
      << "the same move without the scale drift";
  EXPECT_FALSE(options.AllowsCorrection({0.11, 0.1, 0.987}, 1.23, 0.0)) << "the slack is the scene's";
  EXPECT_NEAR(options.MaxMonoCorrection(10.0, 2.0, 1.0), options.MaxMonoCorrection(10.0, 0.5, 1.0), 1e-12)
      << "a scale drifts as far either way";
  EXPECT_TRUE(options.AllowsCorrection({1e6, 1.0, 1.0}, std::numeric_limits<double>::infinity(), 1.0))
      << "no odometry joins the two ends";
}

TEST(LoopBounds, MonocularBoundsTheTurnWhateverTheOdometry) {
  LoopCloserOptions options;
  options.fix_scale = false;
  EXPECT_DOUBLE_EQ(options.MaxRotationDeg(1e6), options.max_mono_loop_rotation_deg);
  EXPECT_TRUE(options.AllowsCorrection({0.5, 29.0, 1.0}, 100.0, 0.0));
  EXPECT_FALSE(options.AllowsCorrection({0.5, 31.0, 1.0}, 100.0, 0.0));
  EXPECT_FALSE(options.AllowsCorrection({0.5, 90.0, 1.0}, 1e6, 0.0));
}

TEST(LoopBounds, CheckRefusesBoundsThatMeanNothing) {
  LoopCloserOptions options;
  EXPECT_NO_THROW(options.Check());
  options.max_mono_loop_rotation_deg = 0.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.max_mono_loop_rotation_deg = 30.0;
  options.stereo_rotation_slack_deg = -1.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.stereo_rotation_slack_deg = 5.0;
  options.max_stereo_rotation_deg_per_100m = -0.1;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.max_stereo_rotation_deg_per_100m = 2.0;
  options.max_depth_ratio = 1.0;  // no transform's depths agree with the points' exactly
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.max_depth_ratio = 1.5;
  options.max_mono_correction_ratio = 0.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.max_mono_correction_ratio = 0.03;
  options.mono_correction_slack_depths = -0.1;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semslam
