// `semslam route` on a topology.json and on a map.semslam whose extra section holds it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "semslam/map/map_file.h"
#include "semslam/topology/topological_map.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using testing::CommandResult;
using ::testing::HasSubstr;
using testing::ReadText;
using testing::RunSemslam;

// An L-shaped drive: 100 m east past the Bakery, left, 80 m north to the School.
TopologicalMap SmallMap() {
  const Georeference g(EnuFrame(Wgs84{49.0, 8.4, 110.0}), Sim3d());
  FramePositions keyframes;
  for (int i = 0; i <= 90; ++i) {
    FramePosition k;
    k.frame_index = static_cast<size_t>(i);
    k.keyframe_id = i;
    k.map_position = i <= 50 ? Eigen::Vector3d(2.0 * i, 0, 0) : Eigen::Vector3d(100, 2.0 * (i - 50), 0);
    keyframes.push_back(k);
  }
  std::vector<PlacedLandmark> landmarks(2);
  landmarks[0].landmark.name = "Bakery";
  landmarks[0].enu = Eigen::Vector3d(30, -8, 0);
  landmarks[1].landmark.name = "Old School";
  landmarks[1].enu = Eigen::Vector3d(108, 80, 0);
  for (PlacedLandmark& l : landmarks) {
    l.landmark.position = g.enu_frame.ToWgs84(l.enu);
    l.landmark.has_altitude = true;
    l.map_position = l.enu;
  }
  return BuildTopologicalMap(keyframes, landmarks, g);
}

class RouteCli : public ::testing::Test {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
  testing::TempDir dir_;
};

TEST_F(RouteCli, PrintsStepsAndWritesGeoJson) {
  const TopologicalMap map = SmallMap();
  WriteTopologyJson(dir_ / "topology.json", map);
  const std::string topology = (dir_ / "topology.json").string();
  CommandResult r = RunSemslam({"route", "--map", topology, "--from", "bakery", "--to", "Old School", "--out",
                                (dir_ / "route.geojson").string()});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_THAT(r.out, HasSubstr("Route from Bakery to Old School, 150 m:"));
  EXPECT_THAT(r.out, HasSubstr("1. Start at Bakery, heading east."));
  EXPECT_THAT(r.out, HasSubstr("2. Drive 70 m."));
  EXPECT_THAT(r.out, HasSubstr("3. Turn left."));
  EXPECT_THAT(r.out, HasSubstr("4. Drive 80 m to Old School (on your right)."));
  const nlohmann::json route = nlohmann::json::parse(ReadText(dir_ / "route.geojson"));
  EXPECT_EQ(route["features"][0]["properties"]["to"], "Old School");

  r = RunSemslam({"route", "--json", "--map", topology, "--from", "Bakery", "--to", "Old School"});
  ASSERT_EQ(r.exit_code, 0);
  EXPECT_NEAR(nlohmann::json::parse(r.out)["length_m"].get<double>(), 150.0, 2.0);

  r = RunSemslam({"route", "--map", topology, "--from", "Bakery", "--to", "Cinema"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("unknown landmark 'Cinema'"));
  r = RunSemslam({"route", "--map", (dir_ / "missing.json").string(), "--from", "A", "--to", "B"});
  EXPECT_EQ(r.exit_code, 1);
}

TEST_F(RouteCli, ReadsTheMapFileSection) {
  const TopologicalMap topology = SmallMap();
  Map empty;
  MapFileContents contents;
  contents.extra_sections["topology"] = TopologyJsonString(topology);
  WriteMapFile(dir_ / "map.semslam", empty, contents);
  CommandResult r = RunSemslam(
      {"route", "--map", (dir_ / "map.semslam").string(), "--from", "Bakery", "--to", "Old School"});
  ASSERT_EQ(r.exit_code, 0) << r.Describe();
  EXPECT_THAT(r.out, HasSubstr("Drive 80 m to Old School"));

  WriteMapFile(dir_ / "bare.semslam", empty, {});
  r = RunSemslam({"route", "--map", (dir_ / "bare.semslam").string(), "--from", "A", "--to", "B"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("no topological map"));
}

}  // namespace
}  // namespace semslam
