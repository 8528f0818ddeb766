// The synthetic route drives as a car does: yaw rate and lateral acceleration within what cars do on the KITTI
// drives (route.h kRouteMaxYawRate, kRouteMaxLateralAcceleration; route.cc gives the KITTI figures), on the
// streets of many towns; it never turns back on itself, and it still loops and passes the town's landmarks.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "semslam/sim/synthetic_city.h"

namespace semslam::sim {
namespace {

constexpr double kDegree = M_PI / 180.0;

struct Dynamics {
  double max_yaw_per_frame = 0;  // rad
  double max_yaw_rate = 0;       // rad/s
  double max_lateral = 0;        // m/s^2
  size_t worst_frame = 0;
};

Dynamics Measure(const Route& route, double rate_hz) {
  Dynamics d;
  for (size_t f = 1; f < route.yaw.size(); ++f) {
    const double step = std::abs(std::remainder(route.yaw[f] - route.yaw[f - 1], 2 * M_PI));
    if (step > d.max_yaw_per_frame) {
      d.max_yaw_per_frame = step;
      d.worst_frame = f;
    }
    // Yaw rate and lateral acceleration between consecutive frames, as a camera at the frame rate sees them.
    const double rate = step * rate_hz;
    d.max_yaw_rate = std::max(d.max_yaw_rate, rate);
    d.max_lateral = std::max(d.max_lateral, rate * 0.5 * (route.speed[f] + route.speed[f - 1]));
  }
  return d;
}

// Seeds 3, 77 and 4242 turned back on a 3.6 m circle (25 deg per frame, 250 deg/s at 8 m/s) before the planner
// stopped turning from a heading the car had not driven yet; every turn was taken at 8 m/s or more (61 deg/s,
// 8.5 m/s^2). Forty towns, 1500 frames each.
TEST(RouteDynamics, WithinTheLimitsOfACarOnEverySeed) {
  double worst_yaw = 0, worst_lateral = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    for (const std::uint64_t town : {seed, seed * 1000 + 242}) {
      SynthOptions o = PresetOptions("default");
      o.city.seed = town;
      o.route.frames = 1500;
      const SyntheticCity sim(o);
      const Route& route = sim.route();
      const Dynamics d = Measure(route, o.route.rate_hz);
      const std::string where = "seed " + std::to_string(town) + ", frame " + std::to_string(d.worst_frame);
      EXPECT_LE(d.max_yaw_rate, kRouteMaxYawRate * 1.01) << where;
      EXPECT_LE(d.max_lateral, kRouteMaxLateralAcceleration * 1.02) << where;
      worst_yaw = std::max(worst_yaw, d.max_yaw_per_frame);
      worst_lateral = std::max(worst_lateral, d.max_lateral);
      // Never back the way it came: no intersection follows the one before the last.
      const std::vector<int>& seq = route.intersections;
      for (size_t k = 2; k < seq.size(); ++k) EXPECT_NE(seq[k], seq[k - 2]) << "seed " << town << ", step " << k;
      // Turns happen: the car does not crawl through the whole town to stay within the limits.
      EXPECT_GE(route.turns.size(), 4u) << "seed " << town;
      EXPECT_GT(route.length, 1200.0) << "seed " << town;
      // Still a drive for SLAM: it comes back to an earlier place (a loop to close) within 1000 frames, the
      // same way round, and passes named places.
      const std::vector<Revisit> revisits = sim.Revisits();
      EXPECT_FALSE(revisits.empty()) << "seed " << town;
      if (!revisits.empty()) {
        EXPECT_LT(revisits.front().frame, 1000) << "seed " << town;
      }
      EXPECT_GE(sim.Landmarks().size(), 8u) << "seed " << town;
    }
  }
  RecordProperty("max_yaw_deg_per_frame", std::to_string(worst_yaw / kDegree));
  RecordProperty("max_lateral_m_s2", std::to_string(worst_lateral));
  EXPECT_LE(worst_yaw, 4.0 * kDegree * 1.01);  // 40 deg/s at 10 Hz
  EXPECT_GT(worst_yaw, 3.0 * kDegree);         // the tightest turns do use the limit
}

// Fleet drives (route seeds) go round the hub and its neighbouring block with the same corners, then on with
// the loops above: the same limits, never back the way they came, and a loop to close early in the drive.
TEST(RouteDynamics, FleetDrivesWithinTheLimitsAndLoop) {
  double worst_yaw = 0, shortest = 1e9;
  int latest_revisit = 0;
  size_t fewest_turns = 1000;
  for (const std::uint64_t town : {1u, 2u, 3u, 4u, 77u, 4242u}) {
    for (std::uint64_t route_seed = 1; route_seed <= 8; ++route_seed) {
      SynthOptions o = PresetOptions("default");
      o.city.seed = town;
      o.route.route_seed = route_seed;
      o.route.frames = 1200;
      const SyntheticCity sim(o);
      const Route& route = sim.route();
      const Dynamics d = Measure(route, o.route.rate_hz);
      const std::string where = "town " + std::to_string(town) + ", route seed " +
                                std::to_string(route_seed) + ", frame " + std::to_string(d.worst_frame);
      EXPECT_LE(d.max_yaw_rate, kRouteMaxYawRate * 1.01) << where;
      EXPECT_LE(d.max_lateral, kRouteMaxLateralAcceleration * 1.02) << where;
      worst_yaw = std::max(worst_yaw, d.max_yaw_per_frame);
      const std::vector<int>& seq = route.intersections;
      for (size_t k = 2; k < seq.size(); ++k) EXPECT_NE(seq[k], seq[k - 2]) << where << ", step " << k;
      fewest_turns = std::min(fewest_turns, route.turns.size());
      shortest = std::min(shortest, route.length);
      const std::vector<Revisit> revisits = sim.Revisits();
      ASSERT_FALSE(revisits.empty()) << where;
      latest_revisit = std::max(latest_revisit, revisits.front().frame);
      EXPECT_GE(sim.Landmarks().size(), 8u) << where;
    }
  }
  RecordProperty("max_yaw_deg_per_frame", std::to_string(worst_yaw / kDegree));
  RecordProperty("latest_first_revisit_frame", std::to_string(latest_revisit));
  RecordProperty("fewest_turns", std::to_string(fewest_turns));
  RecordProperty("shortest_m", std::to_string(shortest));
  EXPECT_LE(worst_yaw, 4.0 * kDegree * 1.01);
  // Measured: the first loop closed by frame 568 at the latest, 8 turns or more, 1001 m or more in 1200
  // frames (more turns than today's drive, which covers 1200 m or more).
  EXPECT_LT(latest_revisit, 600);
  EXPECT_GE(fewest_turns, 6u);
  EXPECT_GT(shortest, 950.0);
}

TEST(RouteDynamics, SeedsOfTheIssue) {
  // The towns issue 9 measured: 4242 (a U-turn, 25.6 deg per frame) and 5150 (6.1 deg per frame at 8 m/s).
  for (const std::uint64_t town : {4242u, 5150u}) {
    SynthOptions o = PresetOptions("default");
    o.city.seed = town;
    o.route.frames = 1500;
    const SyntheticCity sim(o);
    const Dynamics d = Measure(sim.route(), o.route.rate_hz);
    RecordProperty("seed_" + std::to_string(town), std::to_string(d.max_yaw_per_frame / kDegree) +
                                                       " deg per frame, " + std::to_string(d.max_lateral) +
                                                       " m/s^2");
    EXPECT_LE(d.max_yaw_per_frame, 4.0 * kDegree * 1.01) << town;
    EXPECT_LE(d.max_lateral, kRouteMaxLateralAcceleration * 1.02) << town;
  }
}

}  // namespace
}  // namespace semslam::sim
