#pragma once
// Drives of a fleet through one town (RouteOptions::route_seed), planned so that any two of them share
// streets in the same direction and in the opposite one, and keep streets of their own.
//
// The town has a hub: a block whose four neighbouring blocks are drivable, with two blocks of room to the
// drivable border where the town has them, and the shortest way round it and its neighbours (chosen from the
// street grid alone); and a sense of driving round it (counter-clockwise, by left turns, or clockwise, from
// the city seed alone). A drive starts half way along a street one block off the hub, comes to a corner of
// the hub, drives once round it in the hub's sense and along its first side again (a loop to close), then
// straight on into the neighbouring block ahead and round that one in the same sense, which brings it back
// along a side of the hub the other way; then it goes on with the loops of route.h, away from the hub.
// Consecutive route seeds come to the hub at its four corners in turn (so four consecutive drives go round
// four different neighbouring blocks), along the other street off the corner for the next four.
//
// So any two drives share the hub's sides in the same direction, and the side one of them drives back is one
// the other drives the other way (both once each drive has gone round its neighbouring block: by frame 1100
// of a drive at 10 Hz, median 900, in 40 default towns); the street to the hub, the neighbouring block and
// what follows are each drive's own. No turn is a U-turn; every turn is a corner of the street grid, driven
// as route.h drives them.

#include <array>
#include <cstdint>
#include <vector>

#include "semslam/sim/city.h"
#include "semslam/sim/random.h"
#include "semslam/sim/route.h"

namespace semslam::sim {

struct TownHub {
  std::array<int, 4> corners{};  // intersection ids, in the order the drives go round the hub
  bool counter_clockwise = true;
  int drivable_neighbours = 0;  // neighbouring blocks with drivable corners (4 unless the town is small)
};

// Throws InvalidArgument if no block of the town has drivable corners.
TownHub FindTownHub(const StreetGrid& grid, std::uint64_t city_seed);

// The intersections of a fleet drive up to the end of its loop round the hub's neighbouring block (route.cc's
// planner continues from there). `rng` is the drive's own stream.
std::vector<int> PlanHubTour(const StreetGrid& grid, std::uint64_t city_seed, std::uint64_t route_seed,
                             Rng& rng);

// How two drives share the town's streets: metres of street centre line (in 1 m bins of each segment, the
// intersections included) that both drove the same way, that they drove opposite ways, and that one of them
// drove and the other did not. A stretch one drive took both ways and the other one way counts as shared in
// the same and in the opposite direction.
struct RouteOverlap {
  double same_direction = 0;
  double opposite_direction = 0;
  double only_first = 0;
  double only_second = 0;
};
RouteOverlap CompareRoutes(const StreetGrid& grid, const Route& first, const Route& second);

// Metres of street centre line a drive covers (in the bins of CompareRoutes), whichever way.
double DrivenStreetLength(const StreetGrid& grid, const Route& route);

}  // namespace semslam::sim
