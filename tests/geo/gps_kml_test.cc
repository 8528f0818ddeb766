#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "semslam/geo/gps.h"
#include "semslam/io/sequence.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;
using testing::WriteText;

constexpr const char* kHeader = R"(<?xml version="1.0" encoding="utf-8"?>
<kml xmlns="http://www.opengis.net/kml/2.2" xmlns:gx="http://www.google.com/kml/ext/2.2">
<Document>
)";

TEST(GpsKml, UntimedLineStringIsOnePositionPerFrame) {
  TempDir dir;
  const auto file = WriteText(dir / "track.kml", std::string(kHeader) + R"(<Placemark><LineString>
<coordinates>8.40,49.00,110.5 8.41,49.01,111
  8.42,49.02,112.25
</coordinates></LineString></Placemark></Document></kml>
)");
  GpsLog log = ReadGps(file);
  EXPECT_EQ(log.format, "kml");
  ASSERT_EQ(log.fixes.size(), 3u);
  EXPECT_TRUE(log.times_are_frames);
  EXPECT_DOUBLE_EQ(log.fixes[2].timestamp, 2.0);
  EXPECT_DOUBLE_EQ(log.fixes[2].position.longitude_deg, 8.42);
  EXPECT_DOUBLE_EQ(log.fixes[2].position.latitude_deg, 49.02);
  EXPECT_DOUBLE_EQ(log.fixes[2].position.altitude_m, 112.25);

  // Frame k takes frame k's time; positions beyond the sequence are dropped and noted.
  TimeFixesByFrame(log, {10.0, 10.1});
  EXPECT_FALSE(log.times_are_frames);
  ASSERT_EQ(log.fixes.size(), 2u);
  EXPECT_DOUBLE_EQ(log.fixes[1].timestamp, 10.1);
  ASSERT_EQ(log.notes.size(), 1u);
  EXPECT_THAT(log.notes[0], HasSubstr("1 positions beyond"));
}

TEST(GpsKml, TimedTrackAndPlacemarks) {
  TempDir dir;
  const auto track = WriteText(dir / "track.kml", std::string(kHeader) + R"(<Placemark><gx:Track>
<when>2011-09-26T13:02:25.5Z</when><when>2011-09-26T13:02:26.5Z</when>
<gx:coord>8.40 49.00 110</gx:coord><gx:coord>8.41 49.01 111</gx:coord>
</gx:Track></Placemark></Document></kml>)");
  const GpsLog log = ReadGpsKml(track);
  ASSERT_EQ(log.fixes.size(), 2u);
  EXPECT_FALSE(log.times_are_frames);
  EXPECT_DOUBLE_EQ(log.fixes[0].timestamp, 1317042145.5);  // date -d 2011-09-26T13:02:25Z +%s
  EXPECT_DOUBLE_EQ(log.fixes[1].timestamp - log.fixes[0].timestamp, 1.0);

  const auto points = WriteText(dir / "points.kml", std::string(kHeader) + R"(
<Placemark><TimeStamp><when>2020-01-01T00:00:01+01:00</when></TimeStamp><Point><coordinates>8.4,49.0</coordinates></Point></Placemark>
<Placemark><TimeStamp><when>2020-01-01T00:00:00Z</when></TimeStamp><Point><coordinates>8.5,49.1</coordinates></Point></Placemark>
</Document></kml>)");
  const GpsLog p = ReadGpsKml(points);
  ASSERT_EQ(p.fixes.size(), 2u);
  EXPECT_DOUBLE_EQ(p.fixes[0].timestamp, 1577836801.0 - 3600.0);  // date -d 2020-01-01T00:00:01Z +%s
  EXPECT_DOUBLE_EQ(p.fixes[1].position.longitude_deg, 8.5);
}

TEST(GpsKml, MalformedFilesNameTheLine) {
  TempDir dir;
  const auto broken =
      WriteText(dir / "broken.kml", std::string(kHeader) + "<Placemark>\n<LineString>\n</Document>");
  try {
    ReadGpsKml(broken);
    FAIL() << "a malformed KML file was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("broken.kml:6"));
    EXPECT_THAT(e.what(), HasSubstr("well-formed"));
  }
  const auto text =
      WriteText(dir / "text.kml", std::string(kHeader) +
                                      "<Placemark><LineString>\n<coordinates>8.4,49.0 "
                                      "eight,49.1</coordinates></LineString></Placemark></Document></kml>");
  try {
    ReadGpsKml(text);
    FAIL() << "a coordinate that is not a number was read";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("text.kml:5"));
    EXPECT_THAT(e.what(), HasSubstr("lon"));
  }
  const auto empty = WriteText(dir / "empty.kml", std::string(kHeader) + "</Document></kml>");
  EXPECT_THROW(ReadGpsKml(empty), InputError);
  const auto when = WriteText(dir / "when.kml", std::string(kHeader) + R"(<Placemark><gx:Track>
<when>yesterday</when><gx:coord>8.40 49.00 110</gx:coord></gx:Track></Placemark></Document></kml>)");
  EXPECT_THROW(ReadGpsKml(when), InputError);
  // A NaN position is a bad fix, skipped and reported, not read.
  const auto nan = WriteText(dir / "nan.kml", std::string(kHeader) + R"(<Placemark><LineString>
<coordinates>8.4,49.0 nan,49.1 8.5,49.2</coordinates></LineString></Placemark></Document></kml>)");
  const GpsLog log = ReadGpsKml(nan);
  EXPECT_EQ(log.fixes.size(), 2u);
  EXPECT_EQ(log.skipped.size(), 1u);
}

TEST(GpsKml, Iso8601) {
  EXPECT_DOUBLE_EQ(*ParseIso8601Utc("1970-01-02T00:00:00Z"), 86400.0);
  EXPECT_DOUBLE_EQ(*ParseIso8601Utc(" 2000-03-01T12:30:15.25 "), 951913815.25);
  EXPECT_DOUBLE_EQ(*ParseIso8601Utc("2000-03-01T12:30:15-02:00"), 951913815.0 + 7200.0);
  EXPECT_FALSE(ParseIso8601Utc("2000-13-01T00:00:00Z"));
  EXPECT_FALSE(ParseIso8601Utc("2000-01-01"));
  EXPECT_FALSE(ParseIso8601Utc("2000-01-01T00:00:00 CET"));
}

// The published RTK track of KITTI 07: one position per frame of the raw drive behind the sequence.
TEST(GpsKml, KittiRtkTrackOfSequence07) {
  SEMSLAM_REQUIRE_SHARED_DATA(track, "kitti_odom_gps_rtk/RTK_GPS_kitti_07.kml");
  SEMSLAM_REQUIRE_SHARED_DATA(sequence_dir, "kitti_odom_07_3dv/sequences/07");
  GpsLog log = ReadGps(track);
  EXPECT_TRUE(log.skipped.empty());
  ASSERT_EQ(log.fixes.size(), 1106u);
  const auto sequence = OpenSequence(sequence_dir);
  TimeFixesByFrame(log, FrameTimestamps(*sequence, 0, sequence->size()));
  ASSERT_EQ(log.fixes.size(), sequence->size());
  EXPECT_DOUBLE_EQ(log.fixes[100].timestamp, sequence->Timestamp(100));
}

}  // namespace
}  // namespace semslam
