// The bounds a loop within one map must keep against the odometry between its two ends.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "semslam/core/error.h"
#include "semslam/loop/loop_closer.h"

namespace semslam {
namespace {

Eigen::Quaterniond Yaw(double degrees) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitY()));
}

TEST(CorrectionRotation, IsTheAngleBetweenTheTwoOrientationsWhateverTheScale) {
  const Rigid3d before(Yaw(10.0), Eigen::Vector3d(1, 2, 3));
  EXPECT_NEAR(CorrectionRotationDeg(before, Sim3d(0.5, Yaw(90.5), Eigen::Vector3d(7, 0, 0))), 80.5, 1e-9);
  EXPECT_NEAR(CorrectionRotationDeg(before, Sim3d(2.0, Yaw(-5.0), Eigen::Vector3d::Zero())), 15.0, 1e-9);
  EXPECT_NEAR(CorrectionRotationDeg(before, Sim3d(before)), 0.0, 1e-6);
}

// The black-out drive's failing stereo loop: after 366.6 m of odometry the query keyframe matched one 11.25 m and
// 80.5 degrees away across a crossing. Its 12.4 m jump was inside the length bound; its turn is far outside the
// rotation bound, while the true loops of that drive (0.2-0.4 m, a degree) stay inside both.
TEST(LoopBounds, StereoRefusesTheLookAlikeAcrossACrossing) {
  LoopCloserOptions options;
  options.fix_scale = true;
  EXPECT_NEAR(options.MaxStereoCorrectionM(366.6), 14.0, 0.01);
  EXPECT_GT(options.MaxStereoCorrectionM(366.6), 12.4) << "the length bound alone let the look-alike pass";
  EXPECT_NEAR(options.MaxRotationDeg(366.6), 12.33, 0.01);
  EXPECT_LT(options.MaxRotationDeg(366.6), 80.5);
  EXPECT_GT(options.MaxRotationDeg(0.0), 1.0) << "a short loop may still turn a keyframe by its own noise";
  EXPECT_GT(options.MaxRotationDeg(2000.0), options.MaxRotationDeg(100.0)) << "heading drift grows with the path";
}

TEST(LoopBounds, MonocularRotationBoundIgnoresTheUnscaledOdometry) {
  LoopCloserOptions options;
  options.fix_scale = false;
  EXPECT_DOUBLE_EQ(options.MaxRotationDeg(0.0), options.max_mono_loop_rotation_deg);
  EXPECT_DOUBLE_EQ(options.MaxRotationDeg(1e6), options.max_mono_loop_rotation_deg);
  EXPECT_LT(options.MaxRotationDeg(1e6), 80.5);
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
}

}  // namespace
}  // namespace semslam
