#pragma once
// The drive through the town: a sequence of intersections made of rectangular loops around blocks, turned
// alternately left and right; after each loop the car drives the loop's first street again in the same
// direction (a revisit for loop closure) before it leaves for the next one, never turning back on itself. The
// path keeps to the right lane and turns on circular arcs smoothed to continuous curvature. Each street has a
// cruise speed; the car accelerates and brakes at limited rates and takes the turns as slowly as a car's
// yaw rate (40 deg/s) and lateral acceleration (4 m/s^2) limits ask, below the maxima of the KITTI drives
// (see route.cc). Poses are sampled at the camera rate.
//
// With a route seed (RouteOptions::route_seed) the drive is instead one of a fleet's drives through the same
// town (route_tour.h): it starts a block off the town's hub block, loops round the hub and round a block next
// to it, then goes on with loops as above, away from the hub. Such drives share streets with each other both
// ways.

#include <cmath>
#include <cstdint>
#include <vector>

#include "semslam/geometry/rigid3.h"
#include "semslam/sim/city.h"

namespace semslam::sim {

// The dynamics the route keeps to (route.cc gives the KITTI figures behind them).
inline constexpr double kRouteMaxYawRate = 40.0 * M_PI / 180.0;  // rad/s
inline constexpr double kRouteMaxLateralAcceleration = 4.0;      // m/s^2

struct RouteOptions {
  int frames = 1200;
  double rate_hz = 10.0;
  // Cruise speeds per street are drawn from [max(min_speed, 10), max_speed] m/s; turns are slower.
  double min_speed = 8.0;       // m/s
  double max_speed = 12.0;      // m/s
  double camera_height = 1.65;  // above the road
  bool reverse = false;         // drive the same streets in the opposite direction
  std::uint64_t seed = 0;       // 0: the city seed
  // 0: the drive above (today's). Otherwise a fleet drive through the same town (route_tour.h); other values
  // give other drives, with their own GPS and sensor noise (the town, its traffic and its origin stay).
  std::uint64_t route_seed = 0;
  void Check() const;
};

struct RouteTurn {
  int frame = 0;  // the frame nearest to the middle of the turn
  bool left = false;
  int intersection = 0;  // StreetGrid intersection id
};

struct Route {
  std::vector<int> intersections;         // planned, in driving order (the frames may end before the last)
  std::vector<Rigid3d> town_from_camera;  // left camera, per frame
  std::vector<double> speed;              // m/s, per frame
  std::vector<double> yaw;                // heading, rad, counter-clockwise from east (town x)
  std::vector<double> yaw_rate;           // rad/s
  std::vector<double> acceleration;       // along the path, m/s^2
  std::vector<RouteTurn> turns;           // turns reached within the frames
  std::vector<int> frame_segment;         // street segment id the car is on (nearest), per frame
  double length = 0;                      // driven over the frames, metres
};

// Throws InvalidArgument if the town is too small for a loop.
Route PlanRoute(const City& city, const RouteOptions& options);

}  // namespace semslam::sim
