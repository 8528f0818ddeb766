#include "semslam/sim/route_tour.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "semslam/core/error.h"

namespace semslam::sim {
namespace {

constexpr int kDi[4] = {1, 0, -1, 0};  // headings: east, north, west, south (as route.cc)
constexpr int kDj[4] = {0, 1, 0, -1};

// The heading from an intersection to its neighbour.
int Heading(const StreetGrid& g, int from, int to) {
  for (int h = 0; h < 4; ++h) {
    if (g.I(from) + kDi[h] == g.I(to) && g.J(from) + kDj[h] == g.J(to)) return h;
  }
  throw InvalidArgument("route tour: intersections are not neighbours");
}

// The neighbour in a heading, or -1 if it is not drivable.
int Step(const StreetGrid& g, int from, int heading) {
  const int i = g.I(from) + kDi[heading], j = g.J(from) + kDj[heading];
  return g.Drivable(i, j) ? g.IntersectionId(i, j) : -1;
}

// Whether the block between street lines bi..bi+1 and bj..bj+1 has drivable corners.
bool DrivableBlock(const StreetGrid& g, int bi, int bj) {
  return g.Drivable(bi, bj) && g.Drivable(bi + 1, bj + 1);
}

double Perimeter(const StreetGrid& g, int bi, int bj) {
  return 2.0 * (g.xs[static_cast<size_t>(bi + 1)] - g.xs[static_cast<size_t>(bi)] +
                g.ys[static_cast<size_t>(bj + 1)] - g.ys[static_cast<size_t>(bj)]);
}

// Per street segment, 1 m bins along its centre line with bit 1 set where a drive went from segment.a towards
// segment.b, bit 2 where it went the other way.
std::vector<std::vector<std::uint8_t>> Coverage(const StreetGrid& g, const Route& route) {
  std::vector<std::vector<std::uint8_t>> bins(g.segments.size());
  for (const StreetGrid::Segment& s : g.segments)
    bins[static_cast<size_t>(s.id)].assign(static_cast<size_t>(std::max(1.0, std::ceil(s.length))), 0);
  for (size_t f = 1; f < route.town_from_camera.size() && f < route.frame_segment.size(); ++f) {
    const int id = route.frame_segment[f];
    if (id < 0 || route.frame_segment[f - 1] != id) continue;
    const StreetGrid::Segment& s = g.segments[static_cast<size_t>(id)];
    const Eigen::Vector2d a = g.Position(s.a);
    const Eigen::Vector2d axis = (g.Position(s.b) - a).normalized();
    auto along = [&](size_t frame) {
      const double t = (route.town_from_camera[frame].translation.head<2>() - a).dot(axis);
      return std::clamp(t, 0.0, s.length);
    };
    const double t0 = along(f - 1), t1 = along(f);
    std::vector<std::uint8_t>& b = bins[static_cast<size_t>(id)];
    const double per_bin = s.length / static_cast<double>(b.size());
    const auto bin = [&](double t) {
      return std::min(b.size() - 1, static_cast<size_t>(std::max(0.0, std::floor(t / per_bin))));
    };
    const std::uint8_t bit = t1 >= t0 ? 1 : 2;
    for (size_t k = bin(std::min(t0, t1)); k <= bin(std::max(t0, t1)); ++k) b[k] |= bit;
  }
  return bins;
}

}  // namespace

TownHub FindTownHub(const StreetGrid& g, std::uint64_t city_seed) {
  // The hub's neighbouring blocks: west, east, south, north.
  constexpr int kNi[4] = {-1, 1, 0, 0};
  constexpr int kNj[4] = {0, 0, -1, 1};
  double best_cost = std::numeric_limits<double>::max();
  int best_i = -1, best_j = -1, best_neighbours = 0;
  for (int bj = 0; bj + 1 < g.nj(); ++bj) {
    for (int bi = 0; bi + 1 < g.ni(); ++bi) {
      if (!DrivableBlock(g, bi, bj)) continue;
      // Fewer drivable neighbours cost more than any way round; then the way round the hub and its neighbours
      // (a quarter of each neighbour's: a drive goes round one of them).
      int neighbours = 0;
      double cost = Perimeter(g, bi, bj);
      for (int n = 0; n < 4; ++n) {
        if (!DrivableBlock(g, bi + kNi[n], bj + kNj[n])) continue;
        ++neighbours;
        cost += 0.25 * Perimeter(g, bi + kNi[n], bj + kNj[n]);
      }
      cost += 1e7 * (4 - neighbours);
      // Room beyond the neighbours for what follows: blocks to the drivable border, two preferred.
      const int room = std::min({bi - 1, g.ni() - 3 - bi, bj - 1, g.nj() - 3 - bj});
      cost += 1e5 * std::max(0, 2 - room);
      if (cost < best_cost) {
        best_cost = cost;
        best_i = bi;
        best_j = bj;
        best_neighbours = neighbours;
      }
    }
  }
  Require(best_i >= 0, "PlanRoute: the town has no block to drive round");
  TownHub hub;
  hub.counter_clockwise = Rng::Stream(city_seed, 14).Bernoulli(0.5);
  hub.drivable_neighbours = best_neighbours;
  const int sw = g.IntersectionId(best_i, best_j), se = g.IntersectionId(best_i + 1, best_j);
  const int ne = g.IntersectionId(best_i + 1, best_j + 1), nw = g.IntersectionId(best_i, best_j + 1);
  hub.corners =
      hub.counter_clockwise ? std::array<int, 4>{sw, se, ne, nw} : std::array<int, 4>{sw, nw, ne, se};
  return hub;
}

std::vector<int> PlanHubTour(const StreetGrid& g, std::uint64_t city_seed, std::uint64_t route_seed,
                             Rng& rng) {
  const TownHub hub = FindTownHub(g, city_seed);
  auto corner_index = [&](int id) {
    const auto it = std::find(hub.corners.begin(), hub.corners.end(), id);
    return it == hub.corners.end() ? -1 : static_cast<int>(it - hub.corners.begin());
  };
  // Where the drive reaches the hub: consecutive route seeds take the four corners in turn, so that four of
  // them go round four different neighbouring blocks, and the next four come to the same corners along the
  // other street, so that eight of them come to the hub along eight different streets.
  const auto turn_of_town = static_cast<std::uint64_t>(Rng::Stream(city_seed, 15).UniformInt(0, 3));
  const std::uint64_t arrival = route_seed + turn_of_town;
  const int entry = static_cast<int>(arrival % 4);
  const int entry_corner = hub.corners[static_cast<size_t>(entry)];
  std::vector<int> spokes;  // the streets off the hub at that corner
  for (int h = 0; h < 4; ++h) {
    const int v = Step(g, entry_corner, h);
    if (v >= 0 && corner_index(v) < 0) spokes.push_back(v);
  }
  std::vector<int> seq;
  if (spokes.empty()) {
    // A town of one drivable block: the drive starts half way along the hub's side before that corner.
    seq = {hub.corners[static_cast<size_t>((entry + 3) % 4)], entry_corner};
  } else {
    const int spoke = spokes[static_cast<size_t>((arrival / 4) % spokes.size())];
    // The drive starts half way along a street leading to the far end of that one (route.cc starts half way
    // along the first street), not a side of the hub and not turning back. Starts further out would often
    // leave the loop round the hub unclosed in a 600-frame drive.
    std::vector<int> before, any_before;
    for (int h = 0; h < 4; ++h) {
      const int v = Step(g, spoke, h);
      if (v < 0 || v == entry_corner) continue;
      any_before.push_back(v);
      if (corner_index(v) < 0) before.push_back(v);
    }
    if (before.empty()) before = any_before;
    if (before.empty()) {
      seq = {spoke, entry_corner};  // a dead end: the drive starts on the street to the hub
    } else {
      seq = {rng.Pick(before), spoke, entry_corner};
    }
  }

  // Once round the hub and along its first side again. The drive arrives at the hub from a street off it, so
  // the first side is no U-turn.
  for (int k = 1; k <= 4; ++k) seq.push_back(hub.corners[static_cast<size_t>((entry + k) % 4)]);
  // Straight on into the neighbouring block ahead and round it in the hub's sense; its last side is a side of
  // the hub, driven the other way. In a small town the block ahead may not be drivable: then along another
  // side or two of the hub first.
  const int turn = hub.counter_clockwise ? 1 : 3;
  for (int sides = 1; sides <= 3; ++sides) {
    const int corner = hub.corners[static_cast<size_t>((entry + sides) % 4)];
    const int heading = Heading(g, hub.corners[static_cast<size_t>((entry + sides + 3) % 4)], corner);
    const int n1 = Step(g, corner, heading);
    const int n2 = n1 < 0 ? -1 : Step(g, n1, (heading + turn) % 4);
    if (n2 < 0) continue;
    for (int k = 1; k <= sides; ++k) seq.push_back(hub.corners[static_cast<size_t>((entry + k) % 4)]);
    seq.push_back(n1);
    seq.push_back(n2);
    seq.push_back(hub.corners[static_cast<size_t>((entry + sides + 1) % 4)]);
    seq.push_back(corner);
    return seq;
  }
  // No drivable block next to the hub: once more along the first side (a loop to close).
  seq.push_back(hub.corners[static_cast<size_t>((entry + 1) % 4)]);
  return seq;
}

RouteOverlap CompareRoutes(const StreetGrid& g, const Route& first, const Route& second) {
  const auto a = Coverage(g, first), b = Coverage(g, second);
  RouteOverlap o;
  for (const StreetGrid::Segment& s : g.segments) {
    const std::vector<std::uint8_t>& ba = a[static_cast<size_t>(s.id)];
    const std::vector<std::uint8_t>& bb = b[static_cast<size_t>(s.id)];
    const double per_bin = s.length / static_cast<double>(ba.size());
    for (size_t k = 0; k < ba.size(); ++k) {
      const std::uint8_t x = ba[k], y = bb[k];
      const auto flipped = static_cast<std::uint8_t>(((y & 1) << 1) | ((y & 2) >> 1));
      if (x & y) o.same_direction += per_bin;
      if (x & flipped) o.opposite_direction += per_bin;
      if (x && !y) o.only_first += per_bin;
      if (y && !x) o.only_second += per_bin;
    }
  }
  return o;
}

double DrivenStreetLength(const StreetGrid& g, const Route& route) {
  const auto bins = Coverage(g, route);
  double total = 0;
  for (const StreetGrid::Segment& s : g.segments) {
    const std::vector<std::uint8_t>& b = bins[static_cast<size_t>(s.id)];
    const double per_bin = s.length / static_cast<double>(b.size());
    for (const std::uint8_t x : b) total += x ? per_bin : 0.0;
  }
  return total;
}

}  // namespace semslam::sim
