// Checks of a run's inputs before its first frame (system/run_input_checks.h).

#include "semslam/system/run_input_checks.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>
#include <string>

namespace semslam {
namespace {

GpsFix Fix(double t, double lat, double lon) {
  GpsFix fix;
  fix.timestamp = t;
  fix.position = {lat, lon, 0.0};
  return fix;
}

Landmark At(const std::string& name, double lat, double lon) {
  Landmark landmark;
  landmark.name = name;
  landmark.position = {lat, lon, 0.0};
  landmark.source = {"landmarks.csv", 2};
  return landmark;
}

TEST(RunInputChecks, AGpsLogWithoutUsableFixesIsRefused) {
  GpsLog log;
  log.source = "gps.csv";
  EXPECT_THROW(CheckGpsLog(log, {0.0, 0.1}), InputError);
  log.skipped.push_back({{"gps.csv", 2}, "latitude out of range"});
  try {
    CheckGpsLog(log, {0.0, 0.1});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gps.csv:2"), std::string::npos) << e.what();
  }
  log.fixes.push_back(Fix(0.0, 48.1, 11.5));
  EXPECT_NO_THROW(CheckGpsLog(log, {0.0, 0.1}));
}

// The warnings CheckGpsLog gives for `frame_times`.
std::string GpsWarnings(const GpsLog& log, const std::vector<double>& frame_times) {
  std::ostringstream text;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_st>(text);
  spdlog::default_logger()->sinks().push_back(sink);
  CheckGpsLog(log, frame_times);
  spdlog::default_logger()->sinks().pop_back();
  return text.str();
}

TEST(RunInputChecks, ClockTimesThatDoNotOverlapAreWarnedAbout) {
  GpsLog log;
  log.source = "oxts";
  const double start = 1317384000.0;  // a KITTI raw drive's clock
  for (int i = 0; i < 10; ++i) log.fixes.push_back(Fix(start + i, 48.1, 11.5));
  EXPECT_EQ(GpsWarnings(log, {start + 2, start + 3}), "");
  // Times from 0 (KITTI odometry): the log's clock is another base, not another recording.
  EXPECT_EQ(GpsWarnings(log, {0.0, 1.0}), "");
  // Both clocks, 126 s apart: another drive's log.
  const std::string warning = GpsWarnings(log, {start + 126, start + 127});
  EXPECT_NE(warning.find("Is the log of this recording?"), std::string::npos) << warning;
  EXPECT_NE(warning.find("offset -126.000 s"), std::string::npos) << warning;
}

TEST(RunInputChecks, DistancesAreGreatCircles) {
  // One degree of latitude is about 111.2 km.
  EXPECT_NEAR(HorizontalDistanceM({48.0, 11.0, 0}, {49.0, 11.0, 0}), 111195.0, 100.0);
  EXPECT_NEAR(HorizontalDistanceM({0, 0, 0}, {0, 180, 0}), 20015087.0, 1000.0);
}

TEST(RunInputChecks, FarLandmarksAreCounted) {
  GpsLog log;
  for (int i = 0; i < 100; ++i) log.fixes.push_back(Fix(i, 48.1 + i * 1e-5, 11.5));
  const std::vector<Landmark> landmarks = {At("near", 48.1005, 11.5002), At("Null Island", 0.0, 0.0),
                                           At("swapped", 11.5, 48.1)};
  EXPECT_EQ(WarnAboutFarLandmarks(landmarks, "landmarks.csv", log), 2u);
  EXPECT_EQ(WarnAboutFarLandmarks({landmarks[0]}, "landmarks.csv", log), 0u);
  EXPECT_EQ(WarnAboutFarLandmarks(landmarks, "landmarks.csv", std::nullopt), 0u);
}

}  // namespace
}  // namespace semslam
