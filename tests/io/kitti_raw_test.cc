#include "semslam/io/kitti_raw.h"

#include <gtest/gtest.h>

#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

using testing::ReadText;
using testing::WriteText;

constexpr char kRaw[] = "kitti_raw_2011_09_26_drive_0001_oxts";

OxtsRecord MakeRecord(int i) {
  OxtsRecord r;
  r.lat = 49.015003823272 + 1e-5 * i;
  r.lon = 8.4342971002335 - 2e-5 * i;
  r.alt = 116.43032836914;
  r.roll = 0.035752;
  r.pitch = 0.00903;
  r.yaw = -2.6087069803847 + 0.01 * i;
  r.vn = -6.811441479104;
  r.ve = -11.275641809511;
  r.vf = 13.172716663769;
  r.vl = -0.12475264293164;
  r.vu = -0.032919903047354;
  r.ax = -0.44519814607457;
  r.ay = 0.042957369847256;
  r.az = 10.209865300506;
  r.af = -0.34030092211055;
  r.al = -0.31686915378551;
  r.au = 10.209117821189;
  r.wx = 0.0090951755733632;
  r.wy = -0.023140741253985;
  r.wz = -0.017909034508194;
  r.wf = 0.0089018002187228;
  r.wl = -0.022495299354602;
  r.wu = -0.018809330937153;
  r.pos_accuracy = 0.027658633371879 + i;
  r.vel_accuracy = 0.012727922061358;
  r.navstat = 4;
  r.numsats = 11 - i;
  r.posmode = 6;
  r.velmode = 5;
  r.orimode = 6;
  return r;
}

bool SameRecord(const OxtsRecord& a, const OxtsRecord& b) {
  return FormatOxtsLine(a) == FormatOxtsLine(b) && a.lat == b.lat && a.lon == b.lon &&
         a.vel_accuracy == b.vel_accuracy && a.orimode == b.orimode && a.numsats == b.numsats;
}

TEST(Oxts, LineRoundTripIsExact) {
  const OxtsRecord r = MakeRecord(3);
  const std::string line = FormatOxtsLine(r);
  const OxtsRecord back = ParseOxtsLine(line, {"x.txt", 1});
  EXPECT_EQ(back.lat, r.lat);
  EXPECT_EQ(back.lon, r.lon);
  EXPECT_EQ(back.wu, r.wu);
  EXPECT_EQ(back.pos_accuracy, r.pos_accuracy);
  EXPECT_EQ(back.numsats, 8);
  EXPECT_EQ(back.velmode, 5);
  EXPECT_EQ(FormatOxtsLine(back), line);
}

TEST(Oxts, MalformedLines) {
  const SourceLocation where{"data/0000000004.txt", 1};
  std::string line = FormatOxtsLine(MakeRecord(0));
  EXPECT_INPUT_ERROR(ParseOxtsLine(line + " 7", where), "0000000004.txt:1", "expected 30 values", "found 31");
  std::string bad = line;
  bad.replace(0, bad.find(' '), "north");
  EXPECT_INPUT_ERROR(ParseOxtsLine(bad, where), "0000000004.txt:1", "'lat'", "not a number");
  bad = line;
  bad.replace(0, bad.find(' '), "95.5");
  EXPECT_INPUT_ERROR(ParseOxtsLine(bad, where), "'lat'", "outside");
  bad = line.substr(0, line.rfind(' ')) + " 6.5";
  EXPECT_INPUT_ERROR(ParseOxtsLine(bad, where), "'orimode'", "not an integer");
  bad = line.substr(0, line.rfind(' ')) + " 6.0";  // integral floats are accepted
  EXPECT_EQ(ParseOxtsLine(bad, where).orimode, 6);
}

TEST(KittiRawTimestamps, RoundTrip) {
  testing::TempDir dir;
  const std::vector<double> stamps = {0.5, 951782400.25,  // 2000-02-29 (a leap day)
                                      1317042145.964389445, 1317042146.074347616, 1317042157.004854985};
  WriteKittiRawTimestamps(dir / "timestamps.txt", stamps);
  const std::string text = ReadText(dir / "timestamps.txt");
  EXPECT_NE(text.find("2011-09-26 13:02:25.96438"), std::string::npos) << text;
  EXPECT_NE(text.find("1970-01-01 00:00:00.500000000\n"), std::string::npos) << text;
  EXPECT_NE(text.find("2000-02-29 00:00:00.250000000\n"), std::string::npos) << text;
  const std::vector<double> read = ReadKittiRawTimestamps(dir / "timestamps.txt");
  ASSERT_EQ(read.size(), stamps.size());
  for (size_t i = 0; i < stamps.size(); ++i) EXPECT_NEAR(read[i], stamps[i], 1e-6) << i;
}

TEST(KittiRawTimestamps, MalformedLines) {
  testing::TempDir dir;
  const auto file = dir / "timestamps.txt";
  WriteText(file, "2011-09-26 13:02:25.964389445\n2011-09-26 13:02:26\n2011-09-26 13:2:27.1\n");
  EXPECT_INPUT_ERROR(ReadKittiRawTimestamps(file), "timestamps.txt:3", "not a date and time");
  WriteText(file, "2011-02-30 13:02:25.964389445\n");
  EXPECT_INPUT_ERROR(ReadKittiRawTimestamps(file), "timestamps.txt:1", "not a valid date");
  WriteText(file, "2011-09-26 25:02:25.964389445\n");
  EXPECT_INPUT_ERROR(ReadKittiRawTimestamps(file), "timestamps.txt:1", "not a valid time");
  WriteText(file, "2011-09-26 13:02:25.9\n2011-09-26 13:02:25.8\n");
  EXPECT_INPUT_ERROR(ReadKittiRawTimestamps(file), "timestamps.txt:2", "back in time");
  WriteText(file, "2011-09-26 13:02:25.9\n\n2011-09-26 13:02:26.0\n");
  EXPECT_INPUT_ERROR(ReadKittiRawTimestamps(file), "timestamps.txt:2", "blank line");
  // A missing fraction and trailing blank lines are fine.
  WriteText(file, "2011-09-26 13:02:26\n\n");
  EXPECT_EQ(ReadKittiRawTimestamps(file), std::vector<double>{1317042146.0});
}

TEST(OxtsFolder, RoundTrip) {
  testing::TempDir dir;
  std::vector<StampedOxts> readings;
  for (int i = 0; i < 12; ++i) readings.push_back({1317042145.5 + 0.1 * i, MakeRecord(i)});
  WriteOxtsFolder(dir / "oxts", readings);
  EXPECT_TRUE(std::filesystem::exists(dir / "oxts/data/0000000011.txt"));
  const std::vector<StampedOxts> read = ReadOxtsFolder(dir / "oxts");
  ASSERT_EQ(read.size(), readings.size());
  for (size_t i = 0; i < read.size(); ++i) {
    EXPECT_NEAR(read[i].timestamp, readings[i].timestamp, 1e-6);
    EXPECT_TRUE(SameRecord(read[i].record, readings[i].record)) << i;
  }
  // Writing fewer readings over the folder removes the records that no longer have a timestamp.
  readings.resize(5);
  WriteOxtsFolder(dir / "oxts", readings);
  EXPECT_FALSE(std::filesystem::exists(dir / "oxts/data/0000000005.txt"));
  EXPECT_EQ(ReadOxtsFolder(dir / "oxts").size(), 5u);
}

TEST(OxtsFolder, MissingOrExtraRecordsAreErrors) {
  testing::TempDir dir;
  std::vector<StampedOxts> readings;
  for (int i = 0; i < 4; ++i) readings.push_back({100.0 + i, MakeRecord(i)});
  WriteOxtsFolder(dir / "oxts", readings);
  std::filesystem::remove(dir / "oxts/data/0000000002.txt");
  EXPECT_INPUT_ERROR(ReadOxtsFolder(dir / "oxts"), "0000000002.txt", "not found");
  WriteOxtsFolder(dir / "oxts", readings);
  WriteText(dir / "oxts/data/0000000004.txt", FormatOxtsLine(MakeRecord(4)) + "\n");
  EXPECT_INPUT_ERROR(ReadOxtsFolder(dir / "oxts"), "timestamps.txt", "lists 4 timestamps");
  WriteOxtsFolder(dir / "oxts", readings);
  WriteText(dir / "oxts/data/0000000001.txt", "1 2 3\n");
  EXPECT_INPUT_ERROR(ReadOxtsFolder(dir / "oxts"), "0000000001.txt:1", "found 3");
}

TEST(OxtsFolder, RealDrive0001) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, kRaw);
  const auto readings = ReadOxtsFolder(data / "2011_09_26_drive_0001_sync/oxts");
  ASSERT_EQ(readings.size(), 108u);
  // The first record, field by field (oxts/data/0000000000.txt).
  const OxtsRecord& r = readings[0].record;
  EXPECT_DOUBLE_EQ(r.lat, 49.015003823272);
  EXPECT_DOUBLE_EQ(r.lon, 8.4342971002335);
  EXPECT_DOUBLE_EQ(r.alt, 116.43032836914);
  EXPECT_DOUBLE_EQ(r.roll, 0.035752);
  EXPECT_DOUBLE_EQ(r.pitch, 0.00903);
  EXPECT_DOUBLE_EQ(r.yaw, -2.6087069803847);
  EXPECT_DOUBLE_EQ(r.vn, -6.811441479104);
  EXPECT_DOUBLE_EQ(r.ve, -11.275641809511);
  EXPECT_DOUBLE_EQ(r.vf, 13.172716663769);
  EXPECT_DOUBLE_EQ(r.vl, -0.12475264293164);
  EXPECT_DOUBLE_EQ(r.vu, -0.032919903047354);
  EXPECT_DOUBLE_EQ(r.ax, -0.44519814607457);
  EXPECT_DOUBLE_EQ(r.ay, 0.042957369847256);
  EXPECT_DOUBLE_EQ(r.az, 10.209865300506);
  EXPECT_DOUBLE_EQ(r.af, -0.34030092211055);
  EXPECT_DOUBLE_EQ(r.al, -0.31686915378551);
  EXPECT_DOUBLE_EQ(r.au, 10.209117821189);
  EXPECT_DOUBLE_EQ(r.wx, 0.0090951755733632);
  EXPECT_DOUBLE_EQ(r.wy, -0.023140741253985);
  EXPECT_DOUBLE_EQ(r.wz, -0.017909034508194);
  EXPECT_DOUBLE_EQ(r.wf, 0.0089018002187228);
  EXPECT_DOUBLE_EQ(r.wl, -0.022495299354602);
  EXPECT_DOUBLE_EQ(r.wu, -0.018809330937153);
  EXPECT_DOUBLE_EQ(r.pos_accuracy, 0.027658633371879);
  EXPECT_DOUBLE_EQ(r.vel_accuracy, 0.012727922061358);
  EXPECT_EQ(r.navstat, 4);
  EXPECT_EQ(r.numsats, 11);
  EXPECT_EQ(r.posmode, 6);
  EXPECT_EQ(r.velmode, 6);
  EXPECT_EQ(r.orimode, 6);
  // 2011-09-26 13:02:25.964389445 UTC; the last reading 11.04 s later.
  EXPECT_NEAR(readings[0].timestamp, 1317042145.964389445, 1e-6);
  EXPECT_NEAR(readings.back().timestamp, 1317042157.004854985, 1e-6);
  EXPECT_DOUBLE_EQ(readings.back().record.lat, 49.014596344219);
  EXPECT_DOUBLE_EQ(readings.back().record.wu, 0.0027147502397949);
  for (size_t i = 1; i < readings.size(); ++i) {
    const double dt = readings[i].timestamp - readings[i - 1].timestamp;
    EXPECT_GT(dt, 0.05) << i;
    EXPECT_LT(dt, 0.15) << i;
    EXPECT_NEAR(readings[i].record.lat, 49.015, 0.01) << i;
  }
  // Every record written back and read again is identical.
  testing::TempDir dir;
  WriteOxtsFolder(dir / "oxts", readings);
  const auto again = ReadOxtsFolder(dir / "oxts");
  ASSERT_EQ(again.size(), readings.size());
  for (size_t i = 0; i < again.size(); ++i) EXPECT_TRUE(SameRecord(again[i].record, readings[i].record)) << i;

  const auto image_stamps =
      ReadKittiRawTimestamps(data / "2011_09_26_drive_0001_sync/image_00/timestamps.txt");
  ASSERT_EQ(image_stamps.size(), 108u);
  EXPECT_NEAR(image_stamps[0], 1317042145.967790592, 1e-6);
}

TEST(KittiRawCalibration, RealFiles) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, kRaw);
  const KittiRawCalibFile cam = ReadKittiRawCalibFile(data / "calib_cam_to_cam.txt");
  const std::vector<double> p = cam.Get("P_rect_00", 12);
  EXPECT_DOUBLE_EQ(p[0], 721.5377);
  EXPECT_DOUBLE_EQ(p[2], 609.5593);
  EXPECT_DOUBLE_EQ(p[6], 172.854);
  EXPECT_DOUBLE_EQ(cam.Get("P_rect_01", 12)[3], -387.5744);
  EXPECT_EQ(cam.Get("S_rect_00", 2), (std::vector<double>{1242, 375}));
  EXPECT_DOUBLE_EQ(cam.Get("corner_dist", 1)[0], 0.0995);
  EXPECT_INPUT_ERROR(cam.Get("P_rect_00", 9), "calib_cam_to_cam.txt", "P_rect_00",
                     "expected 9 numbers, found 12");
  EXPECT_INPUT_ERROR(cam.Get("P_rect_07", 12), "calib_cam_to_cam.txt", "P_rect_07", "missing");

  const Rigid3d velo_from_imu = ReadKittiRawRigid(data / "calib_imu_to_velo.txt");
  EXPECT_NEAR(velo_from_imu.translation.x(), -0.8086759, 1e-9);
  EXPECT_NEAR(velo_from_imu.translation.z(), -0.7997231, 1e-9);
  EXPECT_NEAR(velo_from_imu.ToMatrix()(1, 2), -1.482298e-02, 1e-5);
  const Rigid3d cam_from_velo = ReadKittiRawRigid(data / "calib_velo_to_cam.txt");
  EXPECT_NEAR(cam_from_velo.translation.y(), -0.07631618, 1e-9);
  // Velodyne x (forward) is camera z (forward).
  EXPECT_NEAR((cam_from_velo.rotation * Eigen::Vector3d::UnitX()).z(), 1.0, 1e-3);
}

TEST(KittiRawCalibration, Malformed) {
  testing::TempDir dir;
  WriteText(dir / "calib_velo_to_cam.txt",
            "calib_time: 15-Mar-2012 11:37:16\nR: 1 0 0 0 1 0 0 0 1\nT: 0 0 x\n");
  EXPECT_INPUT_ERROR(ReadKittiRawRigid(dir / "calib_velo_to_cam.txt"), "calib_velo_to_cam.txt:3", "'T[2]'");
  WriteText(dir / "calib_velo_to_cam.txt", "R: 1 0 0 0 1 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadKittiRawRigid(dir / "calib_velo_to_cam.txt"), "'T'", "missing");
  WriteText(dir / "calib_velo_to_cam.txt", "R: 1 0 0 0 1 0 0 0 3\nT: 0 0 0\n");
  EXPECT_INPUT_ERROR(ReadKittiRawRigid(dir / "calib_velo_to_cam.txt"), "'R'", "not a rotation");
  // Orthonormal but a mirror: x and y swapped.
  WriteText(dir / "calib_velo_to_cam.txt", "T: 0 0 0\nR: 0 1 0 1 0 0 0 0 1\n");
  EXPECT_INPUT_ERROR(ReadKittiRawRigid(dir / "calib_velo_to_cam.txt"), "calib_velo_to_cam.txt:2", "'R'",
                     "reflection");
  WriteText(dir / "calib_cam_to_cam.txt",
            "R_rect_00: -1 0 0 0 1 0 0 0 1\n"
            "P_rect_00: 7.2e+02 0 6.0e+02 0 0 7.2e+02 1.8e+02 0 0 0 1 0\n");
  WriteText(dir / "calib_velo_to_cam.txt", "R: 1 0 0 0 1 0 0 0 1\nT: 0 0 0\n");
  EXPECT_INPUT_ERROR(ReadKittiRawRectifiedCameraFromVelo(dir.path(), 0), "calib_cam_to_cam.txt:1",
                     "'R_rect_00'", "reflection");
  WriteText(dir / "calib_velo_to_cam.txt", "R 1 0 0\n");
  EXPECT_INPUT_ERROR(ReadKittiRawRigid(dir / "calib_velo_to_cam.txt"), "calib_velo_to_cam.txt:1",
                     "key: values");
}

}  // namespace
}  // namespace semslam
