#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>

#include "semslam/topology/routing.h"
#include "semslam/topology/topological_map.h"
#include "support/test_support.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::TempDir;

// Map = half metres, rotated: enu = 2 * Rz(30 deg) * map + (5, 7, 0).
Georeference MakeGeoreference() {
  return Georeference(
      EnuFrame(Wgs84{49.0, 8.4, 110.0}),
      Sim3d(2.0, Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitZ())),
            Eigen::Vector3d(5.0, 7.0, 0.0)));
}

// Keyframes every `step` metres (ENU) through the corners.
FramePositions Drive(const Georeference& g, const std::vector<Eigen::Vector2d>& corners, double step = 2.0) {
  FramePositions keyframes;
  size_t frame = 0;
  for (size_t c = 0; c + 1 < corners.size(); ++c) {
    const Eigen::Vector2d a = corners[c], b = corners[c + 1];
    const int n = static_cast<int>(std::round((b - a).norm() / step));
    for (int i = (c == 0 ? 0 : 1); i <= n; ++i) {
      const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / n);
      FramePosition k;
      k.frame_index = frame;
      k.keyframe_id = static_cast<long long>(frame);
      k.timestamp = 0.1 * static_cast<double>(frame);
      frame += 3;
      k.map_position = g.EnuToMap(Eigen::Vector3d(p.x(), p.y(), 1.5));
      keyframes.push_back(k);
    }
  }
  return keyframes;
}

PlacedLandmark Placed(const Georeference& g, const std::string& name, const Eigen::Vector2d& enu) {
  PlacedLandmark p;
  p.landmark.name = name;
  p.enu = Eigen::Vector3d(enu.x(), enu.y(), 1.5);
  p.landmark.position = g.enu_frame.ToWgs84(p.enu);
  p.landmark.has_altitude = true;
  p.map_position = g.EnuToMap(p.enu);
  return p;
}

// A block driven counter-clockwise, then east again past the start: four left turns, the start corner and the
// bakery passed twice.
struct Block {
  Georeference georeference = MakeGeoreference();
  FramePositions keyframes = Drive(georeference, {{0, 0}, {200, 0}, {200, 100}, {0, 100}, {0, 0}, {150, 0}});
  std::vector<PlacedLandmark> landmarks = {
      Placed(georeference, "Bakery", {100, -10}), Placed(georeference, "Church", {200, 110}),
      Placed(georeference, "School", {60, 110}), Placed(georeference, "Far Tower", {100, 400})};
  TopologicalMap map = BuildTopologicalMap(keyframes, landmarks, georeference);

  int NodeAt(const Eigen::Vector2d& enu) const {
    for (const TopoNode& n : map.nodes) {
      if ((n.enu.head<2>() - enu).norm() < 3.0) return n.id;
    }
    return -1;
  }
};

TEST(TopologicalMap, NodesForLandmarksAndTurnsFusedOnRevisits) {
  const Block b;
  const TopologicalMap& m = b.map;
  // Bakery, Church (+ its corner's turn), School, and the turns at (200, 0), (0, 100), (0, 0).
  EXPECT_EQ(m.nodes.size(), 6u);
  EXPECT_EQ(m.NumLandmarkNodes(), 3);
  EXPECT_EQ(m.NumTurnNodes(), 4);
  const int bakery = b.NodeAt({100, 0}), church = b.NodeAt({200, 100}), school = b.NodeAt({60, 100});
  const int corner1 = b.NodeAt({200, 0}), corner3 = b.NodeAt({0, 100}), start = b.NodeAt({0, 0});
  for (const int id : {bakery, church, school, corner1, corner3, start}) ASSERT_GE(id, 0);
  const auto& church_node = m.nodes[static_cast<size_t>(church)];
  EXPECT_TRUE(church_node.is_landmark && church_node.is_turn);
  EXPECT_EQ(church_node.turn, TurnDirection::kLeft);
  EXPECT_NEAR(church_node.turn_angle_deg, 90.0, 10.0);
  EXPECT_EQ(m.nodes[static_cast<size_t>(start)].turn, TurnDirection::kLeft);
  EXPECT_FALSE(m.nodes[static_cast<size_t>(start)].is_landmark);
  // Revisits: the start corner and the bakery are passed twice, the others once.
  EXPECT_EQ(m.nodes[static_cast<size_t>(start)].passes(), 2);
  EXPECT_EQ(m.nodes[static_cast<size_t>(bakery)].passes(), 2);
  EXPECT_EQ(m.nodes[static_cast<size_t>(school)].passes(), 1);
  EXPECT_EQ(m.NumRevisitedNodes(), 2);
  EXPECT_NEAR(m.nodes[static_cast<size_t>(bakery)].visit_arc_m[0], 100.0, 1.0);
  EXPECT_NEAR(m.nodes[static_cast<size_t>(bakery)].visit_arc_m[1], 700.0, 1.0);
  // The landmark too far from the trajectory has no node.
  ASSERT_EQ(m.landmarks.size(), 4u);
  EXPECT_EQ(m.landmarks[3].node, -1);
  EXPECT_NEAR(m.landmarks[3].distance_m, 300.0, 1e-6);
  EXPECT_EQ(m.landmarks[0].node, bakery);

  // Edges: the block's six sides between the nodes, the start-bakery side driven twice; one cycle.
  EXPECT_EQ(m.edges.size(), 6u);
  EXPECT_EQ(m.CyclomaticNumber(), 1);
  for (const TopoEdge& e : m.edges) {
    const bool twice = (e.from == start && e.to == bakery) || (e.from == bakery && e.to == start);
    EXPECT_EQ(e.traversals, twice ? 2 : 1) << e.from << "-" << e.to;
    const double expected =
        (e.from == school || e.to == school) ? (e.from == church || e.to == church ? 140 : 60) : 100;
    EXPECT_NEAR(e.length_m, expected, 1.0) << e.from << "-" << e.to;  // metres, not map units
    EXPECT_NEAR((e.polyline_enu.front() - m.nodes[static_cast<size_t>(e.from)].enu).norm(), 0.0, 1.0);
    EXPECT_NEAR((e.polyline_enu.back() - m.nodes[static_cast<size_t>(e.to)].enu).norm(), 0.0, 1.0);
  }
  // Node positions in every frame agree.
  for (const TopoNode& n : m.nodes) {
    EXPECT_NEAR((b.georeference.MapToEnu(n.map_position) - n.enu).norm(), 0.0, 1e-9);
    EXPECT_NEAR((b.georeference.enu_frame.ToEnu(n.wgs84) - n.enu).norm(), 0.0, 1e-6);
  }
}

TEST(TopologicalMap, StraightDriveHasNoTurns) {
  const Georeference g = MakeGeoreference();
  const TopologicalMap m = BuildTopologicalMap(Drive(g, {{0, 0}, {300, 0}}), {Placed(g, "A", {150, 5})}, g);
  ASSERT_EQ(m.nodes.size(), 1u);
  EXPECT_EQ(m.NumTurnNodes(), 0);
  EXPECT_TRUE(m.edges.empty());
  TopologyOptions bad;
  bad.turn_threshold_deg = 0;
  EXPECT_THROW(BuildTopologicalMap({}, {}, g, bad), InvalidArgument);
}

TEST(Routing, ShortestRouteAsSteps) {
  const Block b;
  const Route route = FindRoute(b.map, "Bakery", "school");  // case-insensitive
  // West round the block (100 + 100 + 60 m) beats east (100 + 100 + 140 m).
  EXPECT_NEAR(route.length_m, 260.0, 2.0);
  ASSERT_EQ(route.nodes.size(), 4u);
  EXPECT_EQ(route.nodes[1], b.NodeAt({0, 0}));
  EXPECT_EQ(route.nodes[2], b.NodeAt({0, 100}));
  std::vector<std::string> texts;
  for (const RouteStep& s : route.steps) texts.push_back(s.text);
  EXPECT_THAT(texts,
              ::testing::ElementsAre("Start at Bakery, heading west.", "Drive 100 m.", "Turn right.",
                                     "Drive 100 m.", "Turn right.", "Drive 60 m to School (on your left).",
                                     "You have arrived at School (260 m in all)."));
  // The polyline runs from the bakery's node to the school's.
  EXPECT_NEAR((route.polyline_enu.front().head<2>() - Eigen::Vector2d(100, 0)).norm(), 0.0, 1.0);
  EXPECT_NEAR((route.polyline_enu.back().head<2>() - Eigen::Vector2d(60, 100)).norm(), 0.0, 1.0);

  const Route back = FindRoute(b.map, "Church", "Bakery");
  EXPECT_NEAR(back.length_m, 200.0, 2.0);
  EXPECT_EQ(back.steps.front().text, "Start at Church, heading south.");
  EXPECT_EQ(back.steps[2].text, "Turn right.");
  EXPECT_EQ(back.steps[3].text, "Drive 100 m to Bakery (on your left).");

  try {
    FindRoute(b.map, "Bakery", "Cinema");
    ADD_FAILURE();
  } catch (const InvalidArgument& e) {
    EXPECT_THAT(e.what(), HasSubstr("unknown landmark 'Cinema'"));
    EXPECT_THAT(e.what(), HasSubstr("'School'"));
  }
  EXPECT_THROW(FindRoute(b.map, "Bakery", "Far Tower"), InvalidArgument);  // no node
  EXPECT_EQ(FormatDistance(84.0), "85 m");
  EXPECT_EQ(FormatDistance(123.0), "120 m");
  EXPECT_EQ(FormatDistance(7.4), "7 m");
  EXPECT_EQ(FormatDistance(1234.0), "1.2 km");
}

// A landmark 12 m before a corner shares the corner's node, which stays where the streets meet: anchored at
// the landmark, the junction would move 12 m down one street, and a route from the north street to the east
// one would go on to it and turn around (24 m longer).
TEST(Routing, ALandmarkBesideACornerLeavesTheJunctionAtTheCorner) {
  const Georeference g = MakeGeoreference();
  // East through the corner (200, 0), round the block to the north, and back south through the corner,
  // turning right (west) there.
  const FramePositions keyframes = Drive(g, {{0, 0}, {300, 0}, {300, 100}, {200, 100}, {200, 0}, {100, 0}});
  const TopologicalMap m = BuildTopologicalMap(
      keyframes,
      {Placed(g, "Market", {188, -8}), Placed(g, "Tower", {210, 60}), Placed(g, "Depot", {250, -8})}, g);
  ASSERT_EQ(m.landmarks.size(), 3u);
  const TopoNode& market = m.nodes.at(static_cast<size_t>(m.landmarks[0].node));
  EXPECT_TRUE(market.is_turn && market.is_landmark);
  EXPECT_LT((market.enu.head<2>() - Eigen::Vector2d(200, 0)).norm(), 3.0);
  const Route route = FindRoute(m, "Tower", "Depot");
  EXPECT_NEAR(route.length_m, 110.0, 3.0);  // 60 m south to the corner, 50 m east
  for (const RouteStep& step : route.steps) EXPECT_NE(step.turn, TurnDirection::kUTurn) << step.text;
  EXPECT_EQ(route.steps[2].text, "Turn left.");
}

TEST(Routing, UnconnectedPlaces) {
  Block b;
  b.map.edges.clear();
  EXPECT_THROW(FindRoute(b.map, "Bakery", "School"), std::runtime_error);
  EXPECT_TRUE(ShortestPath(b.map, 0, 1).nodes.empty());
  EXPECT_EQ(ShortestPath(b.map, 2, 2).nodes.size(), 1u);
}

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A street of the Block's city through `enu` (metres).
Street MakeStreet(const Georeference& g, const std::string& name, const std::vector<Eigen::Vector2d>& enu) {
  Street s;
  s.name = name;
  s.highway = "residential";
  for (const Eigen::Vector2d& p : enu)
    s.polyline.push_back(g.enu_frame.ToWgs84(Eigen::Vector3d(p.x(), p.y(), 0)));
  return s;
}

// The Block's streets, their centre lines 3 m off its path (a lane): South Street (y = 0), West Street
// (x = 0), North Street (y = 100, east of x = 100) which is Parkside west of it; no street along x = 200. A
// fountain at (100, 110) and the corner of Parkside and West Street as landmarks.
struct StreetBlock : Block {
  StreetBlock() {
    landmarks.push_back(Placed(georeference, "Fountain", {100, 110}));
    PlacedLandmark corner = Placed(georeference, "Parkside / West Street", {-3, 104});
    corner.landmark.category = std::string(kCornerCategory);
    landmarks.push_back(corner);
    streets = {MakeStreet(georeference, "South Street", {{-50, -3}, {120, -3}, {250, -3}}),
               MakeStreet(georeference, "West Street", {{3, -50}, {3, 150}}),
               MakeStreet(georeference, "North Street", {{250, 103}, {100, 103}}),
               MakeStreet(georeference, "Parkside", {{100, 103}, {-50, 103}})};
    map = BuildTopologicalMap(keyframes, landmarks, georeference, {}, streets);
  }
  std::vector<Street> streets;

  const TopoEdge& Edge(const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
    const int na = NodeAt(a), nb = NodeAt(b);
    for (const TopoEdge& e : map.edges) {
      if ((e.from == na && e.to == nb) || (e.from == nb && e.to == na)) return e;
    }
    throw std::runtime_error("no such edge");
  }
};

std::vector<std::string> StepTexts(const Route& route) {
  std::vector<std::string> texts;
  for (const RouteStep& s : route.steps) texts.push_back(s.text);
  return texts;
}

TEST(TopologyStreets, EdgesNamedForTheStreetsTheyFollow) {
  const StreetBlock b;
  EXPECT_EQ(b.Edge({100, 0}, {0, 0}).street, "South Street");
  EXPECT_EQ(b.Edge({0, 0}, {0, 100}).street, "West Street");
  EXPECT_EQ(b.Edge({0, 100}, {60, 100}).street, "Parkside");
  EXPECT_EQ(b.Edge({100, 100}, {200, 100}).street, "North Street");
  EXPECT_EQ(b.Edge({200, 0}, {200, 100}).street, "");  // no street known there
  // A street names a polyline when it is within reach of more than half of it: 75 of 121 samples (the last
  // 60 m along South Street, and round the corner), but 35 of 81 not.
  const std::vector<TopoStreet> enu = StreetsToEnu(b.streets, b.georeference.enu_frame);
  EXPECT_EQ(StreetAlong({{60, 0, 1.5}, {200, 0, 1.5}, {200, 100, 1.5}}, enu, 10.0), "South Street");
  EXPECT_EQ(StreetAlong({{140, 0, 1.5}, {200, 0, 1.5}, {200, 100, 1.5}}, enu, 10.0), "");
  EXPECT_EQ(StreetAlong({{60, 0, 1.5}, {150, 0, 1.5}}, enu, 2.0), "");  // the street is 3 m off
  EXPECT_EQ(StreetAlong({{0, 0, 0}, {100, 0, 0}}, {}, 10.0), "");
}

TEST(TopologyStreets, RoutesNameTheStreets) {
  const StreetBlock b;
  EXPECT_THAT(StepTexts(FindRoute(b.map, "Bakery", "School")),
              ::testing::ElementsAre(
                  "Start at Bakery, heading west.", "Drive 100 m along South Street.",
                  "Turn right into West Street.", "Drive 100 m along West Street to Parkside / West Street.",
                  "Turn right into Parkside.", "Drive 60 m along Parkside to School (on your left).",
                  "You have arrived at School (260 m in all)."));
  // Straight on where the street changes its name; unknown streets are not named.
  EXPECT_THAT(StepTexts(FindRoute(b.map, "School", "Church")),
              ::testing::ElementsAre("Start at School, heading east.",
                                     "Drive 40 m along Parkside to Fountain (on your left).",
                                     "Continue straight into North Street.",
                                     "Drive 100 m along North Street to Church (on your left).",
                                     "You have arrived at Church (140 m in all)."));
  EXPECT_THAT(StepTexts(FindRoute(b.map, "Church", "Bakery")),
              ::testing::ElementsAre("Start at Church, heading south.", "Drive 100 m.",
                                     "Turn right into South Street.",
                                     "Drive 100 m along South Street to Bakery (on your left).",
                                     "You have arrived at Bakery (200 m in all)."));

  // Written and read back; a file written before edges had streets reads with none.
  TempDir dir;
  WriteTopologyFiles(dir.path(), b.map);
  const TopologicalMap back = ReadTopologyJson(dir / "topology.json");
  ASSERT_EQ(back.edges.size(), b.map.edges.size());
  for (size_t i = 0; i < back.edges.size(); ++i) EXPECT_EQ(back.edges[i].street, b.map.edges[i].street);
  EXPECT_EQ(StepTexts(FindRoute(back, "School", "Church")), StepTexts(FindRoute(b.map, "School", "Church")));
  nlohmann::json old = nlohmann::json::parse(TopologyJsonString(b.map));
  for (auto& e : old["edges"]) e.erase("street");
  old["options"].erase("street_max_distance_m");
  const TopologicalMap without = ParseTopologyJson(old.dump(), "old.json");
  for (const TopoEdge& e : without.edges) EXPECT_EQ(e.street, "");
  EXPECT_THAT(StepTexts(FindRoute(without, "Church", "Bakery")),
              ::testing::ElementsAre("Start at Church, heading south.", "Drive 100 m.", "Turn right.",
                                     "Drive 100 m to Bakery (on your left).",
                                     "You have arrived at Bakery (200 m in all)."));
  old["edges"][0]["street"] = 7;
  EXPECT_THROW(ParseTopologyJson(old.dump(), "old.json"), InputError);

  const nlohmann::json geojson = nlohmann::json::parse(ReadAll(dir / "topology.geojson"));
  std::set<std::string> streets;
  for (const auto& f : geojson["features"]) {
    if (f["properties"]["feature"] == "edge") streets.insert(f["properties"]["street"].get<std::string>());
  }
  EXPECT_EQ(streets, (std::set<std::string>{"", "North Street", "Parkside", "South Street", "West Street"}));
  const std::string graphml = ReadAll(dir / "topology.graphml");
  EXPECT_THAT(graphml, HasSubstr("attr.name=\"street\""));
  EXPECT_THAT(graphml, HasSubstr(">West Street<"));
  EXPECT_THAT(ReadAll(dir / "topology.dot"), HasSubstr("West Street, 100 m"));
}

TEST(TopologyFiles, WrittenAndReadBack) {
  const Block b;
  TempDir dir;
  WriteTopologyFiles(dir.path(), b.map);
  const TopologicalMap back = ReadTopologyJson(dir / "topology.json");
  ASSERT_EQ(back.nodes.size(), b.map.nodes.size());
  ASSERT_EQ(back.edges.size(), b.map.edges.size());
  ASSERT_EQ(back.landmarks.size(), b.map.landmarks.size());
  ASSERT_EQ(back.keyframes.size(), b.map.keyframes.size());
  for (size_t i = 0; i < back.nodes.size(); ++i) {
    EXPECT_EQ(back.nodes[i].landmarks, b.map.nodes[i].landmarks);
    EXPECT_EQ(back.nodes[i].turn, b.map.nodes[i].turn);
    EXPECT_EQ(back.nodes[i].visit_keyframes, b.map.nodes[i].visit_keyframes);
    EXPECT_NEAR((back.nodes[i].enu - b.map.nodes[i].enu).norm(), 0.0, 1e-9);
  }
  EXPECT_NEAR(back.georeference.enu_from_map.scale, 2.0, 1e-12);
  // The same route from the file as from memory.
  EXPECT_EQ(FindRoute(back, "Bakery", "School").nodes, FindRoute(b.map, "Bakery", "School").nodes);
  EXPECT_EQ(ParseTopologyJson(TopologyJsonString(b.map), "section").nodes.size(), b.map.nodes.size());

  const nlohmann::json geojson = nlohmann::json::parse(ReadAll(dir / "topology.geojson"));
  int points = 0, lines = 0;
  for (const auto& f : geojson["features"]) {
    (f["geometry"]["type"] == "Point" ? points : lines)++;
  }
  EXPECT_EQ(points, 6 + 4);  // nodes and landmarks
  EXPECT_EQ(lines, 6);
  const std::string graphml = ReadAll(dir / "topology.graphml");
  EXPECT_THAT(graphml, HasSubstr("<graphml"));
  EXPECT_THAT(graphml, HasSubstr("Church"));
  const std::string dot = ReadAll(dir / "topology.dot");
  EXPECT_THAT(dot, HasSubstr("graph G {"));
  size_t dot_edges = 0;
  for (size_t at = dot.find("--"); at != std::string::npos; at = dot.find("--", at + 2)) ++dot_edges;
  EXPECT_EQ(dot_edges, 6u);

  const Route route = FindRoute(b.map, "Bakery", "School");
  WriteRouteGeoJson(dir / "route.geojson", b.map, route);
  const nlohmann::json r = nlohmann::json::parse(ReadAll(dir / "route.geojson"));
  EXPECT_EQ(r["features"][0]["geometry"]["type"], "LineString");
  EXPECT_EQ(r["features"][0]["properties"]["steps"].size(), route.steps.size());
  EXPECT_EQ(r["features"].size(), 1 + route.nodes.size());
}

TEST(TopologyFiles, MalformedJsonNamesTheField) {
  const Block b;
  const nlohmann::json good = nlohmann::json::parse(TopologyJsonString(b.map));
  const auto expect_error = [](const nlohmann::json& j, const std::string& what) {
    try {
      ParseTopologyJson(j.dump(), "t.json");
      ADD_FAILURE() << "no error for " << what;
    } catch (const InputError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  nlohmann::json j = good;
  j["format"] = "other";
  expect_error(j, "field 'format'");
  j = good;
  j["edges"][2]["to"] = 99;
  expect_error(j, "field 'edges[2].to': index 99 out of range");
  j = good;
  j["nodes"][1].erase("enu");
  expect_error(j, "field 'nodes[1].enu': missing");
  j = good;
  j["landmarks"][0]["lat"] = "north";
  expect_error(j, "field 'landmarks[0].lat': expected a finite number");
  j = good;
  j["georeference"]["enu_from_map"]["scale"] = -1;
  expect_error(j, "field 'georeference.enu_from_map.scale'");
  j = good;
  j["nodes"][1]["lat"] = 500;
  expect_error(j, "field 'nodes[1]': not a valid WGS84 position");
  j = good;
  j["keyframes"] = nlohmann::json::array();
  expect_error(j, "anchor_keyframe': index 100, but there is none to refer to");
  try {
    ParseTopologyJson("{\n\"format\":\n", "t.json");
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("t.json:3: field 'json'"));
  }
  EXPECT_THROW(ReadTopologyJson("/nonexistent/topology.json"), InputError);
}

}  // namespace
}  // namespace semslam
