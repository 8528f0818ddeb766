#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/system/sequence_runner.h"
#include "semslam/system/slam_config.h"
#include "semslam/system/slam_system.h"
#include "support/test_support.h"

namespace semslam {
namespace {

TEST(SlamOptions, ModeAndPacingNames) {
  EXPECT_EQ(ParseSensorMode("mono"), SensorMode::kMonocular);
  EXPECT_EQ(ParseSensorMode("stereo"), SensorMode::kStereo);
  EXPECT_FALSE(ParseSensorMode("Stereo").has_value());
  for (const Pacing pacing : {Pacing::kFast, Pacing::kRealtime, Pacing::kSynchronous})
    EXPECT_EQ(ParsePacing(PacingName(pacing)), pacing);
  EXPECT_EQ(PacingName(Pacing::kSynchronous), "synchronous");
  EXPECT_FALSE(ParsePacing("slow").has_value());
}

TEST(SlamOptions, ConfigPacingReadWrittenAndRejected) {
  testing::TempDir dir;
  std::ofstream(dir / "good.yaml") << "tracking:\n  pacing: synchronous\n";
  SlamOptions options;
  ApplySlamConfig(dir / "good.yaml", &options);
  EXPECT_EQ(options.pacing, Pacing::kSynchronous);
  EXPECT_NE(SlamConfigToYaml(options).find("pacing: synchronous"), std::string::npos);

  std::ofstream(dir / "bad.yaml") << "tracking:\n  pacing: slow\n";
  try {
    ApplySlamConfig(dir / "bad.yaml", &options);
    FAIL() << "a bad pacing was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("fast, realtime or synchronous"), std::string::npos) << e.what();
  }
  EXPECT_EQ(options.pacing, Pacing::kSynchronous);
}

TEST(SlamOptions, RealtimeWaitForMappingIsBounded) {
  SlamOptions options;
  EXPECT_NO_THROW(options.Check());
  for (const double frames : {-0.5, 10.5, std::nan("")}) {
    options.realtime_wait_for_mapping_frames = frames;
    EXPECT_THROW(options.Check(), InvalidArgument) << frames;
  }
  options.realtime_wait_for_mapping_frames = 0.0;  // never wait
  EXPECT_NO_THROW(options.Check());
}

// A value the options' own checks refuse is reported at its line in the file, under its key.
TEST(SlamOptions, ConfigRangeErrorsNameTheLineAndKey) {
  testing::TempDir dir;
  std::ofstream(dir / "range.yaml")
      << "tracking:\n  pacing: fast\nfeatures:\n  scale_factor: 1.2\n  num_features: 0\n";
  SlamOptions options;
  try {
    ApplySlamConfig(dir / "range.yaml", &options);
    FAIL() << "num_features 0 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("range.yaml:5: field 'features.num_features'"), std::string::npos)
        << e.what();
  }
}

// A key an earlier version read is refused with what replaced it, at its line; the new key is read.
TEST(SlamOptions, ConfigRenamedKeyNamesItsReplacement) {
  testing::TempDir dir;
  std::ofstream(dir / "old.yaml") << "tracking:\n  pacing: fast\n  min_frames_between_keyframes: 3\n";
  SlamOptions options;
  try {
    ApplySlamConfig(dir / "old.yaml", &options);
    FAIL() << "a renamed key was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("old.yaml:3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("now tracking.min_seconds_between_keyframes"), std::string::npos)
        << e.what();
  }
  std::ofstream(dir / "new.yaml") << "tracking:\n  min_seconds_between_keyframes: 0.5\n";
  ApplySlamConfig(dir / "new.yaml", &options);
  EXPECT_EQ(options.tracker.min_seconds_between_keyframes, 0.5);
}

// Options that mean nothing without another are refused, not silently ignored.
TEST(RunOptions, FlagsThatNeedAnotherAreRefused) {
  RunOptions options;
  options.sequence = "seq";
  options.output = "out";
  EXPECT_NO_THROW(options.Check());
  options.slam.localization_only = true;
  try {
    options.Check();
    ADD_FAILURE() << "--localization-only without a map was accepted";
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("--map-in"), std::string::npos) << e.what();
  }
  options.map_in = "map.semslam";
  EXPECT_NO_THROW(options.Check());
  options.slam.exclude_dynamic = true;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options.segmenter = "truth-noisy:0.1";
  EXPECT_NO_THROW(options.Check());
  options.slam.tracker.min_seconds_between_keyframes = 1.5;  // above max_seconds_between_keyframes
  EXPECT_THROW(options.Check(), InvalidArgument);
}

// A camera height that cannot scale the objects is refused before the run, not after its last frame.
TEST(RunOptions, CameraHeightIsAPositiveLength) {
  RunOptions options;
  options.sequence = "seq";
  options.output = "out";
  EXPECT_EQ(options.camera_height_m, 1.65);
  for (const double bad : {0.0, -1.65, std::numeric_limits<double>::infinity(), std::nan("")}) {
    options.camera_height_m = bad;
    EXPECT_THROW(options.Check(), InvalidArgument) << bad;
  }
  options.camera_height_m = 2.4;
  EXPECT_NO_THROW(options.Check());
}

}  // namespace
}  // namespace semslam
