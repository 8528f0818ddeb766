// The ratio of units across a gap in a drive, from the speed on its two sides.
#include "semslam/geometry/scale_across_gap.h"

#include <gtest/gtest.h>

#include "semslam/core/error.h"

namespace semslam {
namespace {

// A car on a straight road at `speed` (m/s) at t = 0 with a constant `acceleration` (m/s^2), sampled at
// `times`, its positions divided by `units` (metres per map unit).
Trajectory Drive(const std::vector<double>& times, double speed, double acceleration, double units) {
  Trajectory drive;
  for (const double t : times) {
    const double metres = speed * t + 0.5 * acceleration * t * t;
    drive.push_back(
        {t, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(metres, 0.2 * metres, 0.0) / units)});
  }
  return drive;
}

TEST(FitScaleAcrossGap, GivesTheRatioOfUnitsOfACarThatSpeedsUpOverTheGap) {
  // 5 m/s at t = 0, 1.5 m/s^2 (leaving a junction); no pose from 1.0 s to 3.2 s; uneven keyframe times.
  const std::vector<double> before_times = {0.0, 0.3, 0.4, 0.7, 0.8, 1.0};
  const std::vector<double> after_times = {3.2, 3.3, 3.5, 3.6, 3.9, 4.1};
  const double metres_per_unit_before = 2.0, metres_per_unit_after = 0.8;
  const auto fit = FitScaleAcrossGap(Drive(before_times, 5.0, 1.5, metres_per_unit_before),
                                     Drive(after_times, 5.0, 1.5, metres_per_unit_after));
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(*fit, metres_per_unit_after / metres_per_unit_before, 1e-9);
}

TEST(FitScaleAcrossGap, ReadsABrakingCarRightWhereTheMeanSpeedsOfTheSidesDoNot) {
  // 10 m/s braking at 2 m/s^2: the mean speeds of the sides differ 3.75x where their units differ 1.25x.
  const std::vector<double> before_times = {0.0, 0.2, 0.4, 0.6, 0.8, 1.0};
  const std::vector<double> after_times = {3.0, 3.2, 3.4, 3.6, 3.8, 4.0};
  const auto fit =
      FitScaleAcrossGap(Drive(before_times, 10.0, -2.0, 1.0), Drive(after_times, 10.0, -2.0, 1.25));
  ASSERT_TRUE(fit.has_value());
  EXPECT_NEAR(*fit, 1.25, 1e-9);
}

TEST(FitScaleAcrossGap, GivesNothingWhereTheFitIsUndetermined) {
  const std::vector<double> two = {0.0, 0.5}, three_before = {0.0, 0.5, 1.0}, three_after = {3.0, 3.5, 4.0};
  // One step on a side.
  EXPECT_FALSE(FitScaleAcrossGap(Drive(two, 5.0, 0.0, 1.0), Drive(three_after, 5.0, 0.0, 1.0)).has_value());
  EXPECT_FALSE(
      FitScaleAcrossGap(Drive(three_before, 5.0, 0.0, 1.0), Drive({3.0, 3.5}, 5.0, 0.0, 1.0)).has_value());
  // Standing still after the gap: no ratio.
  EXPECT_FALSE(
      FitScaleAcrossGap(Drive(three_before, 5.0, 0.0, 1.0), Drive(three_after, 0.0, 0.0, 1.0)).has_value());
  // Positions at one time give no step.
  EXPECT_FALSE(FitScaleAcrossGap(Drive({0.0, 0.5, 0.5}, 5.0, 0.0, 1.0), Drive(three_after, 5.0, 0.0, 1.0))
                   .has_value());
}

TEST(FitScaleAcrossGap, RejectsPositionsOutOfTimeOrder) {
  const std::vector<double> before_times = {0.0, 0.5, 1.0}, after_times = {3.0, 3.5, 4.0};
  EXPECT_THROW(FitScaleAcrossGap(Drive({0.0, 1.0, 0.5}, 5.0, 0.0, 1.0), Drive(after_times, 5.0, 0.0, 1.0)),
               InvalidArgument);
  EXPECT_THROW(FitScaleAcrossGap(Drive(before_times, 5.0, 0.0, 1.0), Drive({0.5, 1.5, 2.0}, 5.0, 0.0, 1.0)),
               InvalidArgument);
}

}  // namespace
}  // namespace semslam
