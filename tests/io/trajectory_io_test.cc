#include "semslam/io/trajectory_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "semslam/core/error.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

using testing::ReadText;
using testing::WriteText;

Trajectory MakeTrajectory(int n) {
  Trajectory trajectory;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector6d twist;
    twist << 1.5 * i, -0.25 * i, 100.0 + 0.75 * i, 0.1 * i, -0.05 * i, 0.3 + 0.02 * i;
    trajectory.push_back({1317042145.5 + 0.1 * i, Rigid3d::Exp(twist)});
  }
  return trajectory;
}

void ExpectSamePose(const Rigid3d& a, const Rigid3d& b, double tolerance) {
  EXPECT_LT((a.translation - b.translation).norm(), tolerance);
  EXPECT_LT(a.rotation.angularDistance(b.rotation), tolerance);
}

TEST(TumTrajectory, RoundTrip) {
  testing::TempDir dir;
  const Trajectory written = MakeTrajectory(20);
  WriteTumTrajectory(dir / "t.tum", written);
  const Trajectory read = ReadTumTrajectory(dir / "t.tum");
  ASSERT_EQ(read.size(), written.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_NEAR(read[i].timestamp, written[i].timestamp, 1e-6);
    ExpectSamePose(read[i].world_from_camera, written[i].world_from_camera, 1e-9);
  }
  EXPECT_EQ(DetectTrajectoryFormat(dir / "t.tum"), TrajectoryFormat::kTum);
}

TEST(TumTrajectory, EmptyTrajectoryRoundTrips) {
  testing::TempDir dir;
  WriteTumTrajectory(dir / "t.tum", {});
  EXPECT_TRUE(ReadTumTrajectory(dir / "t.tum").empty());
}

TEST(TumTrajectory, CommentsBlankLinesAndSmallQuaternionDeviation) {
  testing::TempDir dir;
  // The second quaternion has norm 1.001 (rounded text): it is normalized, not rejected.
  WriteText(dir / "t.tum",
            "# written by hand\n\n1.0 1 2 3 0 0 0 1\n  # indented comment\n2.0 4 5 6 0 0 0.7078 0.7078\n");
  const Trajectory t = ReadTumTrajectory(dir / "t.tum");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[1].timestamp, 2.0);
  EXPECT_EQ(t[1].world_from_camera.translation, Eigen::Vector3d(4, 5, 6));
  EXPECT_NEAR(t[1].world_from_camera.rotation.norm(), 1.0, 1e-12);
  EXPECT_NEAR(t[1].world_from_camera.RotationAngle(), M_PI / 2, 1e-9);
}

TEST(TumTrajectory, MalformedLinesNameFileLineAndField) {
  testing::TempDir dir;
  const auto file = dir / "bad.tum";
  const std::string good = "# header\n0.0 0 0 0 0 0 0 1\n";
  WriteText(file, good + "0.1 0 0 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(file), "bad.tum:3", "columns", "found 7");
  WriteText(file, good + "0.1 0 zero 0 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(file), "bad.tum:3", "'ty'", "not a number");
  WriteText(file, good + "0.1 0 0 nan 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(file), "bad.tum:3", "'tz'", "not finite");
  WriteText(file, good + "0.1 0 0 0 0 0 0 inf\n");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(file), "bad.tum:3", "'qw'", "not finite");
  WriteText(file, good + "0.1 0 0 0 1 1 0 0\n");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(file), "bad.tum:3", "quaternion", "norm 1.41");
  WriteText(file, good + "0.1 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(file), "bad.tum:4", "'timestamp'", "must increase");
  EXPECT_INPUT_ERROR(ReadTumTrajectory(dir / "missing.tum"), "missing.tum", "not found");
}

TEST(KittiPoses, RoundTrip) {
  testing::TempDir dir;
  const Trajectory trajectory = MakeTrajectory(15);
  WriteKittiPoses(dir / "p.txt", trajectory);
  const std::vector<Rigid3d> read = ReadKittiPoses(dir / "p.txt");
  ASSERT_EQ(read.size(), trajectory.size());
  for (size_t i = 0; i < read.size(); ++i) ExpectSamePose(read[i], trajectory[i].world_from_camera, 1e-9);
  EXPECT_EQ(DetectTrajectoryFormat(dir / "p.txt"), TrajectoryFormat::kKitti);

  std::vector<Rigid3d> poses;
  for (const auto& p : trajectory) poses.push_back(p.world_from_camera);
  WriteKittiPoses(dir / "q.txt", poses);
  EXPECT_EQ(ReadText(dir / "p.txt"), ReadText(dir / "q.txt"));
}

TEST(KittiPoses, MalformedLinesNameFileLineAndField) {
  testing::TempDir dir;
  const auto file = dir / "07.txt";
  const std::string identity = "1 0 0 0 0 1 0 0 0 0 1 0\n";
  WriteText(file, identity + "1 0 0 0 0 1 0 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadKittiPoses(file), "07.txt:2", "columns", "found 11");
  WriteText(file, identity + identity + "1 0 0 0 0 1 0 0 0 0 1 x\n");
  EXPECT_INPUT_ERROR(ReadKittiPoses(file), "07.txt:3", "'tz'", "not a number");
  WriteText(file, identity + "1 0 0 0 0 1 0 nan 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiPoses(file), "07.txt:2", "'ty'", "not finite");
  WriteText(file, identity + "2 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiPoses(file), "07.txt:2", "not orthonormal");
  WriteText(file, identity + "-1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiPoses(file), "07.txt:2", "reflection");
}

TEST(Times, RoundTripAndErrors) {
  testing::TempDir dir;
  const std::vector<double> times = {0.0, 0.1036633, 0.2073266, 1317042145.964389};
  WriteTimes(dir / "times.txt", times);
  const std::vector<double> read = ReadTimes(dir / "times.txt");
  ASSERT_EQ(read.size(), times.size());
  for (size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(read[i], times[i], 1e-9 * std::max(1.0, times[i]));

  WriteText(dir / "times.txt", "0.0\n0.1\n0.1\n");
  EXPECT_INPUT_ERROR(ReadTimes(dir / "times.txt"), "times.txt:3", "must increase");
  WriteText(dir / "times.txt", "0.0\n0.1 0.2\n");
  EXPECT_INPUT_ERROR(ReadTimes(dir / "times.txt"), "times.txt:2", "one timestamp per line");
}

TEST(ReadTrajectory, KittiTakesTimestampsFromTimesOrIndex) {
  testing::TempDir dir;
  WriteKittiPoses(dir / "p.txt", MakeTrajectory(3));
  WriteTimes(dir / "times.txt", {10.0, 10.1, 10.2, 10.3, 10.4});  // more stamps than poses: fine
  const Trajectory with_times = ReadTrajectory(dir / "p.txt", dir / "times.txt");
  ASSERT_EQ(with_times.size(), 3u);
  EXPECT_DOUBLE_EQ(with_times[2].timestamp, 10.2);
  const Trajectory by_index = ReadTrajectory(dir / "p.txt");
  EXPECT_DOUBLE_EQ(by_index[2].timestamp, 2.0);

  WriteTimes(dir / "short.txt", {10.0, 10.1});
  EXPECT_INPUT_ERROR(ReadTrajectory(dir / "p.txt", dir / "short.txt"), "short.txt", "fewer than the 3 poses");

  WriteText(dir / "odd.txt", "# comment\n1 2 3 4 5\n");
  EXPECT_INPUT_ERROR(DetectTrajectoryFormat(dir / "odd.txt"), "odd.txt:2", "found 5 numbers");
  WriteText(dir / "empty.txt", "# nothing\n");
  EXPECT_INPUT_ERROR(DetectTrajectoryFormat(dir / "empty.txt"), "empty.txt", "no poses");
}

TEST(KittiPoses, RealSequence07) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, "kitti_odom_07_3dv");
  const std::vector<Rigid3d> poses = ReadKittiPoses(data / "poses/07.txt");
  ASSERT_EQ(poses.size(), 1101u);
  EXPECT_LT(poses[0].translation.norm(), 1e-9);
  EXPECT_LT(poses[0].RotationAngle(), 1e-9);
  EXPECT_NEAR(poses[159].translation.x(), -76.96463, 1e-5);
  EXPECT_NEAR(poses[159].translation.y(), 0.9352274, 1e-7);
  EXPECT_NEAR(poses[159].translation.z(), 15.68785, 1e-5);
  const std::vector<double> times = ReadTimes(data / "sequences/07/times.txt");
  ASSERT_EQ(times.size(), 1101u);
  EXPECT_DOUBLE_EQ(times[0], 0.0);
  EXPECT_DOUBLE_EQ(times[11], 1.142127);
  EXPECT_DOUBLE_EQ(times.back(), 114.3296);
}

}  // namespace
}  // namespace semslam
