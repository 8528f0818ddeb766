// The real KITTI raw drive 2011_09_26_0001 oxts log (108 fixes, read in place from ../shared/data).

#include <gtest/gtest.h>

#include <cmath>

#include "semslam/geo/gps.h"
#include "semslam/io/kitti_raw.h"
#include "support/test_support.h"

namespace semslam {
namespace {

constexpr const char* kDrive = "kitti_raw_2011_09_26_drive_0001_oxts/2011_09_26_drive_0001_sync";

TEST(GpsOxtsReal, EnuRoundTripWithinAMillimetre) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive);
  const GpsLog log = ReadGps(drive);  // the drive folder holds oxts/
  EXPECT_EQ(log.format, "oxts");
  ASSERT_EQ(log.fixes.size(), 108u);
  EXPECT_TRUE(log.skipped.empty());
  const EnuFrame frame = MakeEnuFrame(log);
  EXPECT_LT(frame.ToEnu(log.fixes.front().position).norm(), 1e-9);  // origin at the first fix
  double worst = 0.0;
  for (const GpsFix& fix : log.fixes) {
    const Eigen::Vector3d enu = frame.ToEnu(fix.position);
    const Wgs84 back = frame.ToWgs84(enu);
    // Back to ENU again: the round trip error in metres.
    worst = std::max(worst, (frame.ToEnu(back) - enu).norm());
    // And in angles: 1 mm is about 9e-9 degrees of latitude.
    EXPECT_NEAR(back.latitude_deg, fix.position.latitude_deg, 1e-9);
    EXPECT_NEAR(back.longitude_deg, fix.position.longitude_deg, 1e-9);
    EXPECT_NEAR(back.altitude_m, fix.position.altitude_m, 1e-3);
  }
  EXPECT_LT(worst, 1e-3);
}

TEST(GpsOxtsReal, PathLengthAgreesWithIntegratedForwardSpeed) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive);
  const GpsLog log = ReadGpsOxts(drive / "oxts");
  const std::vector<StampedOxts> raw = ReadOxtsFolder(drive / "oxts");
  ASSERT_EQ(raw.size(), log.fixes.size());
  const EnuFrame frame = MakeEnuFrame(log);
  const Points3d enu = FixesToEnu(log.fixes, frame);
  double path = 0.0, integrated = 0.0;
  for (size_t i = 1; i < enu.size(); ++i) {
    path += (enu[i] - enu[i - 1]).norm();
    const double dt = raw[i].timestamp - raw[i - 1].timestamp;
    ASSERT_GT(dt, 0.0);
    integrated += 0.5 * (raw[i].record.vf + raw[i - 1].record.vf) * dt;  // trapezoid rule
  }
  RecordProperty("enu_path_m", std::to_string(path));
  RecordProperty("integrated_vf_m", std::to_string(integrated));
  EXPECT_GT(path, 50.0);
  EXPECT_NEAR(path / integrated, 1.0, 0.02) << "path " << path << " m, integrated vf " << integrated << " m";
}

TEST(GpsOxtsReal, CameraFramesMatchFixesByTimestamp) {
  SEMSLAM_REQUIRE_SHARED_DATA(drive, kDrive);
  const GpsLog log = ReadGpsOxts(drive);
  const std::vector<double> frames = ReadKittiRawTimestamps(drive / "image_00" / "timestamps.txt");
  ASSERT_EQ(frames.size(), 108u);
  EXPECT_DOUBLE_EQ(GuessTimeOffset(log.fixes, frames), 0.0);  // same Unix time base
  const auto matches = MatchFixesToTimes(log.fixes, frames, 0.02);
  for (size_t i = 0; i < frames.size(); ++i) {
    ASSERT_TRUE(matches[i]) << "frame " << i;
    EXPECT_EQ(*matches[i], i);  // camera and oxts run in step at 10 Hz
  }
}

}  // namespace
}  // namespace semslam
