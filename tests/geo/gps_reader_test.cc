#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "semslam/geo/gps.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

using ::testing::HasSubstr;
using testing::TempDir;
using testing::WriteText;

std::string Nmea(const std::string& body) {
  unsigned checksum = 0;
  for (const char c : body) checksum ^= static_cast<unsigned char>(c);
  return fmt::format("${}*{:02X}", body, checksum);
}

TEST(GpsCsv, ReadsWithAndWithoutHeader) {
  TempDir dir;
  const auto plain =
      WriteText(dir / "plain.csv",
                "0.0,49.0,8.4\n0.1,49.00001,8.40001,115.5,0.7\n\n# comment\n0.2,49.00002,8.40002,,\n");
  const GpsLog log = ReadGpsCsv(plain);
  ASSERT_EQ(log.fixes.size(), 3u);
  EXPECT_TRUE(log.skipped.empty());
  EXPECT_EQ(log.format, "csv");
  EXPECT_DOUBLE_EQ(log.fixes[1].position.altitude_m, 115.5);
  EXPECT_DOUBLE_EQ(log.fixes[1].sigma_m, 0.7);
  EXPECT_DOUBLE_EQ(log.fixes[2].sigma_m, GpsReadOptions{}.default_sigma_m);
  EXPECT_EQ(log.fixes[2].source.line, 5);

  const auto header =
      WriteText(dir / "header.csv", "lon, latitude ,\"time\",sigma\n8.4,49.0,10.0,2.0\n8.5,49.1,11.0,3.0\n");
  const GpsLog h = ReadGpsCsv(header);
  ASSERT_EQ(h.fixes.size(), 2u);
  EXPECT_DOUBLE_EQ(h.fixes[1].timestamp, 11.0);
  EXPECT_DOUBLE_EQ(h.fixes[1].position.latitude_deg, 49.1);
  EXPECT_DOUBLE_EQ(h.fixes[1].position.longitude_deg, 8.5);
  EXPECT_DOUBLE_EQ(h.fixes[1].sigma_m, 3.0);
}

TEST(GpsCsv, BadFixesAreSkippedAndReported) {
  TempDir dir;
  const auto file = WriteText(dir / "bad.csv",
                              "t,lat,lon,alt,sigma\n"
                              "0,49,8,100,1\n"
                              "1,nan,8,100,1\n"   // NaN
                              "2,91,8,100,1\n"    // latitude out of range
                              "3,49,181,100,1\n"  // longitude out of range
                              "1.5,49,8,100,1\n"  // goes back in time
                              "4,49,8,100,-1\n"   // negative sigma
                              "5,49,8,1e6,1\n"    // altitude out of range
                              "6,49,8,100,1\n");
  const GpsLog log = ReadGpsCsv(file);
  ASSERT_EQ(log.fixes.size(), 2u);
  EXPECT_DOUBLE_EQ(log.fixes[1].timestamp, 6.0);
  ASSERT_EQ(log.skipped.size(), 6u);
  EXPECT_EQ(log.skipped[0].where.line, 3);
  EXPECT_THAT(log.skipped[0].reason, HasSubstr("not finite"));
  EXPECT_THAT(log.skipped[1].reason, HasSubstr("latitude"));
  EXPECT_THAT(log.skipped[2].reason, HasSubstr("longitude"));
  EXPECT_THAT(log.skipped[3].reason, HasSubstr("non-monotonic"));
  EXPECT_EQ(log.skipped[3].where.line, 6);
  EXPECT_THAT(log.skipped[4].reason, HasSubstr("sigma"));
  EXPECT_THAT(log.skipped[5].reason, HasSubstr("altitude"));
}

TEST(GpsCsv, MalformedFilesThrowWithLineAndField) {
  TempDir dir;
  const auto expect_error = [&](const std::string& name, const std::string& text, const std::string& what) {
    const auto file = WriteText(dir / name, text);
    try {
      ReadGpsCsv(file);
      ADD_FAILURE() << "no error for " << name;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what)) << name;
    }
  };
  expect_error("text.csv", "0,49,8\n1,49.1,eight\n", "text.csv:2: field 'lon'");
  expect_error("columns.csv", "0,49\n", "columns.csv:1: field 'columns'");
  expect_error("columns2.csv", "0,49,8,1,1,1\n", "columns2.csv:1: field 'columns'");
  expect_error("header.csv", "time,lat,height\n", "header.csv:1: field 'header'");
  expect_error("quote.csv", "\"0,49,8\n", "quote.csv:1");
  EXPECT_THROW(ReadGpsCsv(dir / "missing.csv"), InputError);
}

TEST(GpsNmea, ParsesTheTextbookGga) {
  TempDir dir;
  // The classic example sentence, checksum 47 as published.
  const auto file =
      WriteText(dir / "a.nmea", "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\n");
  const GpsLog log = ReadGpsNmea(file);
  EXPECT_EQ(log.format, "nmea");
  ASSERT_EQ(log.fixes.size(), 1u);
  EXPECT_NEAR(log.fixes[0].position.latitude_deg, 48.0 + 7.038 / 60.0, 1e-12);
  EXPECT_NEAR(log.fixes[0].position.longitude_deg, 11.0 + 31.0 / 60.0, 1e-12);
  EXPECT_NEAR(log.fixes[0].position.altitude_m, 545.4 + 46.9, 1e-9);
  EXPECT_NEAR(log.fixes[0].timestamp, 12 * 3600 + 35 * 60 + 19, 1e-9);
  EXPECT_NEAR(log.fixes[0].sigma_m, 0.9 * GpsReadOptions{}.nmea_uere_m, 1e-12);
}

TEST(GpsNmea, SkipsBadSentencesAndUsesTheRmcDate) {
  TempDir dir;
  std::string text;
  text += Nmea("GPRMC,235959.50,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W") + "\n";  // 1994-03-23
  text += Nmea("GPGGA,235959.50,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") + "\n";     // 2: ok
  text += Nmea("GNGGA,000000.50,4807.040,S,01131.000,W,2,08,1.2,545.4,M,,M,,") + "\n";  // 3: ok, next day
  text += "$GPGGA,000001.50,4807.040,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*00\n";     // 4: bad checksum
  text += Nmea("GPGGA,000002.50,4807.040,N,01131.000,E,0,00,99.9,545.4,M,46.9,M,,") + "\n";  // 5: no fix
  text += "$GPGGA,000003.50,4807.040,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,\n";             // 6: no checksum
  text += Nmea("GPGSV,3,1,11,03,03,111,00,04,15,270,00,06,01,010,00,13,06,292,00") + "\n";   // ignored
  text += Nmea("GPGGA,000004.50,48xx.040,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") + "\n";   // 8: malformed
  text += Nmea("GPGGA,000005.50,4807.040,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") + "\n";   // 9: ok
  text += "garbage\n";                                                                       // 10
  text +=
      Nmea("GPGGA,000004.00,4807.040,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,") + "\n";  // 11: back in time
  const auto file = WriteText(dir / "log.nmea", text);
  const GpsLog log = ReadGpsNmea(file);
  ASSERT_EQ(log.fixes.size(), 3u);
  const double day = 764380800.0;  // 1994-03-23T00:00:00Z
  EXPECT_NEAR(log.fixes[0].timestamp, day + 86399.5, 1e-6);
  EXPECT_NEAR(log.fixes[1].timestamp, day + 86400.5, 1e-6);
  EXPECT_NEAR(log.fixes[2].timestamp, day + 86405.5, 1e-6);
  EXPECT_LT(log.fixes[1].position.latitude_deg, 0);
  EXPECT_LT(log.fixes[1].position.longitude_deg, 0);
  EXPECT_NEAR(log.fixes[1].position.altitude_m, 545.4, 1e-9);  // no geoid separation given
  ASSERT_EQ(log.skipped.size(), 6u);
  EXPECT_EQ(log.skipped[0].where.line, 4);
  EXPECT_THAT(log.skipped[0].reason, HasSubstr("checksum"));
  EXPECT_EQ(log.skipped[1].where.line, 5);
  EXPECT_THAT(log.skipped[1].reason, HasSubstr("quality"));
  EXPECT_EQ(log.skipped[2].where.line, 6);
  EXPECT_THAT(log.skipped[2].reason, HasSubstr("without a checksum"));
  EXPECT_EQ(log.skipped[3].where.line, 8);
  EXPECT_EQ(log.skipped[4].where.line, 10);
  EXPECT_EQ(log.skipped[5].where.line, 11);
  EXPECT_THAT(log.skipped[5].reason, HasSubstr("non-monotonic"));
}

TEST(GpsNmea, DayStartFromOptions) {
  TempDir dir;
  const auto file =
      WriteText(dir / "a.nmea", Nmea("GPGGA,000010,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"));
  GpsReadOptions options;
  options.nmea_day_start_unix = 1000.0;
  EXPECT_NEAR(ReadGpsNmea(file, options).fixes.at(0).timestamp, 1010.0, 1e-9);
  options.nmea_require_checksum = false;
  const auto unchecked =
      WriteText(dir / "b.nmea", "$GPGGA,000010,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,\n");
  EXPECT_EQ(ReadGpsNmea(unchecked, options).fixes.size(), 1u);
}

TEST(GpsMatching, NearestWithinTolerance) {
  std::vector<GpsFix> fixes;
  for (int i = 0; i < 10; ++i) fixes.push_back(GpsFix{100.0 + i, Wgs84{49, 8, 0}, 1.0, {}});
  const auto m = MatchFixesToTimes(fixes, {99.5, 100.04, 103.6, 104.5, 109.04, 109.2, 200}, 0.45);
  ASSERT_EQ(m.size(), 7u);
  EXPECT_FALSE(m[0]);
  EXPECT_EQ(m[1], 0u);
  EXPECT_EQ(m[2], 4u);
  EXPECT_FALSE(m[3]);  // 0.5 s from either
  EXPECT_EQ(m[4], 9u);
  EXPECT_EQ(m[5], 9u);
  EXPECT_FALSE(m[6]);
  const auto shifted = MatchFixesToTimes(fixes, {0.0, 3.0}, 0.01, 100.0);
  EXPECT_EQ(shifted[0], 0u);
  EXPECT_EQ(shifted[1], 3u);
  EXPECT_DOUBLE_EQ(GuessTimeOffset(fixes, {0.0, 0.1, 5.0}), 100.0);
  EXPECT_DOUBLE_EQ(GuessTimeOffset(fixes, {100.0, 101.0}), 0.0);
}

TEST(GpsEnu, OriginAtTheFirstFixUnlessGiven) {
  GpsLog log;
  log.fixes.push_back(GpsFix{0, Wgs84{49.0, 8.4, 110}, 1, {}});
  log.fixes.push_back(GpsFix{1, Wgs84{49.001, 8.4, 110}, 1, {}});
  const EnuFrame frame = MakeEnuFrame(log);
  const Points3d enu = FixesToEnu(log.fixes, frame);
  EXPECT_LT(enu[0].norm(), 1e-9);
  EXPECT_NEAR(enu[1].y(), 111.2, 0.2);  // 0.001 deg of latitude
  EXPECT_NEAR(enu[1].x(), 0.0, 1e-6);
  const EnuFrame given = MakeEnuFrame(log, Wgs84{49.001, 8.4, 110});
  EXPECT_LT(given.ToEnu(log.fixes[1].position).norm(), 1e-9);
  EXPECT_THROW(MakeEnuFrame(GpsLog{}), InputError);
}

}  // namespace
}  // namespace semslam
