// Drives of a fleet through one town (--route-seed): the same town, origin and landmarks for every drive,
// other poses; any two drives share streets in the same and in the opposite direction and keep streets of
// their own; without a route seed the drive is today's, pose for pose.

#include "semslam/sim/route_tour.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "semslam/semantics/class_table.h"
#include "semslam/sim/dataset_writer.h"
#include "semslam/sim/scene_file.h"
#include "semslam/sim/synthetic_city.h"
#include "support/test_support.h"

namespace semslam::sim {
namespace {

SynthOptions Drive(std::uint64_t route_seed, int frames, std::uint64_t town = 1) {
  SynthOptions o = PresetOptions("default");
  o.city.seed = town;
  o.route.frames = frames;
  o.route.route_seed = route_seed;
  o.camera.width = 310;
  o.camera.height = 94;
  o.camera.focal = 718.856 / 4;
  return o;
}

bool SameTown(const City& a, const City& b) {
  if (a.grid.xs != b.grid.xs || a.grid.ys != b.grid.ys) return false;
  if (a.primitives.size() != b.primitives.size() || a.places.size() != b.places.size()) return false;
  for (size_t i = 0; i < a.primitives.size(); ++i) {
    const Primitive& p = a.primitives[i];
    const Primitive& q = b.primitives[i];
    if (p.lo != q.lo || p.hi != q.hi || p.label != q.label || p.shape != q.shape || p.variant != q.variant)
      return false;
  }
  for (size_t i = 0; i < a.places.size(); ++i) {
    if (a.places[i].name != b.places[i].name || a.places[i].position != b.places[i].position) return false;
  }
  return true;
}

TEST(FleetDrives, SameTownOriginAndLandmarksOtherPoses) {
  const SyntheticCity a(Drive(1, 300)), b(Drive(2, 300));
  EXPECT_TRUE(SameTown(a.city(), b.city()));
  // The same ENU origin: a town point has the same WGS84 position in both drives.
  const Eigen::Vector3d town_point(123.0, -45.0, 2.0);
  const Wgs84 wa = a.ToWgs84(a.WorldFromTown() * town_point), wb = b.ToWgs84(b.WorldFromTown() * town_point);
  EXPECT_NEAR(wa.latitude_deg, wb.latitude_deg, 1e-12);
  EXPECT_NEAR(wa.longitude_deg, wb.longitude_deg, 1e-12);
  EXPECT_NEAR(wa.altitude_m, wb.altitude_m, 1e-9);
  // Each catalogue lists the places along its own drive; a place both list has the same coordinates.
  std::map<std::string, Wgs84> listed;
  for (const RouteLandmark& l : a.Landmarks()) listed[l.place->name] = l.wgs84;
  int common = 0;
  for (const RouteLandmark& l : b.Landmarks()) {
    const auto it = listed.find(l.place->name);
    if (it == listed.end()) continue;
    ++common;
    EXPECT_EQ(it->second.latitude_deg, l.wgs84.latitude_deg) << l.place->name;
    EXPECT_EQ(it->second.longitude_deg, l.wgs84.longitude_deg) << l.place->name;
  }
  EXPECT_GE(common, 3);  // measured 8 of 8 and 8
  // Other poses: other starts, and other ways through the town.
  const Route& ra = a.route();
  const Route& rb = b.route();
  EXPECT_GT((ra.town_from_camera[0].translation - rb.town_from_camera[0].translation).norm(), 30.0);
  EXPECT_NE(ra.intersections, rb.intersections);
  // Both drives are rendered from the same scene: the road under the first camera, in either world frame.
  EXPECT_EQ(a.ClassAt(Eigen::Vector3d(0, 1.65, 5)).label, TrainId(SemanticClass::kRoad));
  EXPECT_EQ(b.ClassAt(Eigen::Vector3d(0, 1.65, 5)).label, TrainId(SemanticClass::kRoad));
}

TEST(FleetDrives, TrafficSeedStillChangesOnlyTheParkedCars) {
  SynthOptions o = Drive(3, 200);
  const SyntheticCity plain(o);
  o.city.traffic_seed = 7;
  const SyntheticCity other_traffic(o);
  EXPECT_EQ(plain.city().grid.xs, other_traffic.city().grid.xs);
  EXPECT_NE(plain.city().primitives.size(), other_traffic.city().primitives.size());
  for (size_t f = 0; f < 200; f += 40) {
    EXPECT_EQ((plain.route().town_from_camera[f].translation -
               other_traffic.route().town_from_camera[f].translation)
                  .norm(),
              0.0)
        << f;
  }
}

// Per pair of route seeds 1-8 in twelve towns, at the default 1200 frames and at 600: metres of street shared
// the same way, the opposite way, and driven by one of the two only (CompareRoutes). The route geometry only:
// no rendering. Towns 1-3, route seeds 1-4 are recorded as properties (docs: the figures of the report).
TEST(FleetDrives, AnyTwoShareStreetsBothWaysAndKeepStreetsOfTheirOwn) {
  double min_same[2] = {1e9, 1e9}, min_opposite = 1e9, min_own[2] = {1e9, 1e9};
  for (std::uint64_t town = 1; town <= 12; ++town) {
    CityOptions city_options;
    city_options.seed = town;
    const City city = GenerateCity(city_options);
    for (const int frames : {1200, 600}) {
      const int k = frames == 1200 ? 0 : 1;
      std::vector<Route> routes;
      for (std::uint64_t seed = 1; seed <= 8; ++seed) {
        RouteOptions r;
        r.frames = frames;
        r.route_seed = seed;
        routes.push_back(PlanRoute(city, r));
      }
      for (size_t x = 0; x < routes.size(); ++x) {
        for (size_t y = x + 1; y < routes.size(); ++y) {
          const RouteOverlap o = CompareRoutes(city.grid, routes[x], routes[y]);
          const std::string pair = "town " + std::to_string(town) + ", " + std::to_string(frames) +
                                   " frames, route seeds " + std::to_string(x + 1) + "/" +
                                   std::to_string(y + 1);
          if (town <= 3 && y < 4) {
            RecordProperty(pair, std::to_string(o.same_direction) + " same, " +
                                     std::to_string(o.opposite_direction) + " opposite, " +
                                     std::to_string(o.only_first) + " / " + std::to_string(o.only_second) +
                                     " own");
          }
          // The hub's way round (4 sides of 60 m or more, less the corners) in the same direction.
          EXPECT_GE(o.same_direction, 200.0) << pair;
          // Once round the neighbouring block: a side of the hub the other way (60 m or more, less the
          // corners; measured 52 m at the least).
          if (frames == 1200) {
            EXPECT_GE(o.opposite_direction, 40.0) << pair;
          }
          // Streets of their own: the street to the hub at least.
          EXPECT_GE(o.only_first, 50.0) << pair;
          EXPECT_GE(o.only_second, 50.0) << pair;
          min_same[k] = std::min(min_same[k], o.same_direction);
          if (frames == 1200) min_opposite = std::min(min_opposite, o.opposite_direction);
          min_own[k] = std::min({min_own[k], o.only_first, o.only_second});
        }
      }
    }
  }
  RecordProperty("min_same_m_1200", std::to_string(min_same[0]));
  RecordProperty("min_opposite_m_1200", std::to_string(min_opposite));
  RecordProperty("min_own_m_1200", std::to_string(min_own[0]));
  RecordProperty("min_same_m_600", std::to_string(min_same[1]));
  RecordProperty("min_own_m_600", std::to_string(min_own[1]));
}

// Small towns have fewer (or no) drivable blocks around the hub: the drives still plan, never turn back, and
// go round the hub.
TEST(FleetDrives, SmallTowns) {
  for (const auto& [blocks_x, blocks_y] : std::vector<std::pair<int, int>>{{3, 3}, {3, 4}, {4, 4}, {5, 5}}) {
    CityOptions city_options;
    city_options.blocks_x = blocks_x;
    city_options.blocks_y = blocks_y;
    const City city = GenerateCity(city_options);
    const TownHub hub = FindTownHub(city.grid, city_options.seed);
    for (std::uint64_t seed = 1; seed <= 8; ++seed) {
      RouteOptions r;
      r.frames = 600;
      r.route_seed = seed;
      const Route route = PlanRoute(city, r);
      const std::vector<int>& seq = route.intersections;
      const std::string where = std::to_string(blocks_x) + "x" + std::to_string(blocks_y) +
                                " blocks, route seed " + std::to_string(seed);
      for (size_t k = 2; k < seq.size(); ++k) EXPECT_NE(seq[k], seq[k - 2]) << where << ", step " << k;
      for (const int corner : hub.corners)
        EXPECT_NE(std::find(seq.begin(), seq.end(), corner), seq.end()) << where;
    }
  }
}

// Poses of today's drive (no route seed), measured on the code before route seeds existed (commit 909564a):
// world_from_camera translations of the default town's 1200-frame drive and of town 5's.
TEST(FleetDrives, WithoutARouteSeedTheDriveIsTodays) {
  struct Expected {
    std::uint64_t town;
    size_t frame;
    Eigen::Vector3d position;
  };
  const std::vector<Expected> expected = {
      {1, 1, {1.136868377216e-13, 0.0, 1.081444246967}},
      {1, 250, {-132.0321129775, 0.0, 120.2}},
      {1, 600, {-1.611665353590, 0.0, 41.01571880888}},
      {1, 900, {-184.0, 0.0, 139.6399737925}},
      {1, 1199, {-84.04040684030, 0.0, 122.8295718434}},
      {5, 1, {0.0, 0.0, 1.127760625553}},
      {5, 250, {59.30, 0.0, 53.96022541231}},
      {5, 600, {62.90, 0.0, 190.6405896414}},
      {5, 900, {-110.6551204004, 0.0, 111.6000356796}},
      {5, 1199, {52.60131836946, 0.0, 208.1976477321}},
  };
  for (const std::uint64_t town : {1u, 5u}) {
    SynthOptions o = PresetOptions("default");
    o.city.seed = town;
    o.route.frames = 1200;
    const City city = GenerateCity(o.city);
    const Route route = PlanRoute(city, o.route);
    ASSERT_EQ(route.town_from_camera.size(), 1200u);
    const Rigid3d world_from_town = route.town_from_camera.front().Inverse();
    for (const Expected& e : expected) {
      if (e.town != town) continue;
      const Eigen::Vector3d world = world_from_town * route.town_from_camera[e.frame].translation;
      EXPECT_LT((world - e.position).norm(), 1e-6) << "town " << town << ", frame " << e.frame;
    }
  }
}

TEST(FleetDrives, SceneJsonRecordsTheRouteSeedOnlyWhenGiven) {
  SynthOptions o = Drive(0, 20);
  o.preset = "small";
  o.city = PresetOptions("small").city;
  const SyntheticCity today(o);
  o.route.route_seed = 4;
  const SyntheticCity fleet(o);
  const std::string scene0 = SceneJson(today), scene4 = SceneJson(fleet);
  const auto j0 = nlohmann::json::parse(scene0);
  const auto j4 = nlohmann::json::parse(scene4);
  EXPECT_FALSE(j0["options"]["route"].contains("route_seed"));
  EXPECT_EQ(j4["options"]["route"]["route_seed"], 4);
  EXPECT_EQ(j0["origin"], j4["origin"]);
  // Read back, the options give the same drive.
  testing::TempDir dir;
  std::ofstream(dir / "scene.json") << scene4;
  const SynthOptions read = ReadSceneOptions(dir / "scene.json");
  EXPECT_EQ(read.route.route_seed, 4u);
  const SyntheticCity again(read);
  ASSERT_EQ(again.num_frames(), 20u);
  for (size_t f = 0; f < 20; f += 5) {
    EXPECT_LT((again.route().town_from_camera[f].translation - fleet.route().town_from_camera[f].translation)
                  .norm(),
              1e-12);
  }
  std::ofstream(dir / "scene0.json") << scene0;
  EXPECT_EQ(ReadSceneOptions(dir / "scene0.json").route.route_seed, 0u);
}

}  // namespace
}  // namespace semslam::sim
