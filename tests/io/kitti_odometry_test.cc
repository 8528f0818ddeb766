#include "semslam/io/kitti_odometry.h"

#include <gtest/gtest.h>

#include "semslam/core/error.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

using testing::WriteText;

StereoRig MakeRig() {
  StereoRig rig;
  rig.left.width = 640;
  rig.left.height = 480;
  rig.left.fx = 500.25;
  rig.left.fy = 501.5;
  rig.left.cx = 319.75;
  rig.left.cy = 240.125;
  rig.baseline = 0.54;
  return rig;
}

TEST(KittiCalibration, MakeWriteReadRoundTrip) {
  testing::TempDir dir;
  const StereoRig rig = MakeRig();
  KittiCalibration calibration = MakeKittiCalibration(rig);
  EXPECT_EQ(calibration.num_projections, 4);
  EXPECT_DOUBLE_EQ(calibration.projection[1](0, 3), -500.25 * 0.54);
  calibration.velo_to_cam =
      Rigid3d::Exp((Eigen::Vector6d() << 0.1, 0.2, 0.3, 0.01, 0.02, 0.03).finished()).ToMatrix();
  WriteKittiCalibration(dir / "calib.txt", calibration);
  const KittiCalibration read = ReadKittiCalibration(dir / "calib.txt");
  EXPECT_EQ(read.num_projections, 4);
  for (int i = 0; i < 4; ++i) EXPECT_LT((read.projection[i] - calibration.projection[i]).norm(), 1e-9) << i;
  ASSERT_TRUE(read.velo_to_cam.has_value());
  EXPECT_LT((*read.velo_to_cam - *calibration.velo_to_cam).norm(), 1e-9);

  const auto stereo = read.Stereo01(640, 480);
  ASSERT_TRUE(stereo.has_value());
  EXPECT_NEAR(stereo->baseline, 0.54, 1e-12);
  EXPECT_DOUBLE_EQ(stereo->left.fy, 501.5);
  EXPECT_DOUBLE_EQ(stereo->left.cy, 240.125);
  EXPECT_EQ(stereo->left.width, 640);
}

TEST(KittiCalibration, OnlyP0AndP1) {
  testing::TempDir dir;
  KittiCalibration calibration = MakeKittiCalibration(MakeRig());
  calibration.num_projections = 2;
  WriteKittiCalibration(dir / "calib.txt", calibration);
  const KittiCalibration read = ReadKittiCalibration(dir / "calib.txt");
  EXPECT_EQ(read.num_projections, 2);
  EXPECT_FALSE(read.velo_to_cam.has_value());
  EXPECT_TRUE(read.projection[2].isZero());
  calibration.num_projections = 1;
  WriteKittiCalibration(dir / "mono.txt", calibration);
  EXPECT_FALSE(ReadKittiCalibration(dir / "mono.txt").Stereo01(640, 480).has_value());
}

TEST(KittiCalibration, Malformed) {
  testing::TempDir dir;
  const auto file = dir / "calib.txt";
  const std::string p0 = "P0: 700 0 600 0 0 700 180 0 0 0 1 0\n";
  WriteText(file, p0 + "P1: 700 0 600 -378 0 700 180 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:2", "'P1'", "found 11");
  WriteText(file, p0 + "P1: 700 0 600 -378 0 700 180 0 0 0 1 zero\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:2", "'P1[11]'", "not a number");
  WriteText(file, "P1: 700 0 600 -378 0 700 180 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt", "'P0'", "missing");
  WriteText(file, p0 + "P2: 700 0 600 -378 0 700 180 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:2", "'P2'", "without P1");
  WriteText(file, p0 + "P1: 700 0 600 378 0 700 180 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:2", "baseline");
  WriteText(file, p0 + "P1: 710 0 600 -378 0 710 180 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:2", "not a rectified stereo pair");
  WriteText(file, "\n" + p0 + p0);
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:3", "given twice");
  WriteText(file, "P0: -700 0 600 0 0 700 180 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:1", "focal lengths must be positive");
  WriteText(file, "P0 700 0 600 0 0 700 180 0 0 0 1 0\n");
  EXPECT_INPUT_ERROR(ReadKittiCalibration(file), "calib.txt:1", "KEY: numbers");
}

TEST(KittiCalibration, RealSequences) {
  SEMSLAM_REQUIRE_SHARED_DATA(seq07, "kitti_odom_07_3dv");
  const KittiCalibration c07 = ReadKittiCalibration(seq07 / "sequences/07/calib.txt");
  EXPECT_EQ(c07.num_projections, 4);
  const auto rig07 = c07.Stereo01(1226, 370);
  ASSERT_TRUE(rig07.has_value());
  EXPECT_DOUBLE_EQ(rig07->left.fx, 707.0912);
  EXPECT_DOUBLE_EQ(rig07->left.cx, 601.8873);
  EXPECT_DOUBLE_EQ(rig07->left.cy, 183.1104);
  EXPECT_NEAR(rig07->baseline, 379.8145 / 707.0912, 1e-12);

  SEMSLAM_REQUIRE_SHARED_DATA(seq00, "kitti_odom_00_pyslam");
  const KittiCalibration c00 = ReadKittiCalibration(seq00 / "sequences/00/calib.txt");
  EXPECT_EQ(c00.num_projections, 2);
  EXPECT_NEAR(c00.Stereo01(1241, 376)->baseline, 386.1448 / 718.856, 1e-12);
}

}  // namespace
}  // namespace semslam
