// The topological map of KITTI odometry sequence 00 built from its RTK GPS track (as the keyframes of a
// perfectly georeferenced map) with the corners and streets of its OpenStreetMap extract. The extract and the
// track are not in ../shared/data: run by hand with SEMSLAM_OSM_MAPS=DIR holding kitti_00.osm and
// RTK_GPS_kitti_00.kml.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "semslam/topology/routing.h"
#include "semslam/topology/topological_map.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;

// The first `count` points of the KML LineString (lon,lat,alt each).
std::vector<Wgs84> ReadKmlTrack(const fs::path& file, size_t count) {
  std::ifstream in(file);
  std::stringstream text;
  text << in.rdbuf();
  const std::string k = text.str();
  const size_t begin = k.find("<coordinates>"), end = k.find("</coordinates>");
  std::vector<Wgs84> track;
  if (begin == std::string::npos || end == std::string::npos) return track;
  std::istringstream coordinates(k.substr(begin + 13, end - begin - 13));
  for (std::string point; coordinates >> point && track.size() < count;) {
    double lon = 0, lat = 0, alt = 0;
    if (std::sscanf(point.c_str(), "%lf,%lf,%lf", &lon, &lat, &alt) != 3) break;
    track.push_back(Wgs84{lat, lon, alt});
  }
  return track;
}

TEST(TopologyOsm, KittiOdometry00ByHand) {
  const char* maps = std::getenv("SEMSLAM_OSM_MAPS");
  if (maps == nullptr) GTEST_SKIP() << "set SEMSLAM_OSM_MAPS to the folder of kitti_00.osm";
  const std::vector<Wgs84> track = ReadKmlTrack(fs::path(maps) / "RTK_GPS_kitti_00.kml", 1700);
  ASSERT_EQ(track.size(), 1700u);
  const Georeference g(EnuFrame(track.front()),
                       Sim3d(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()));
  FramePositions keyframes;
  for (size_t i = 0; i < track.size(); i += 5) {  // a keyframe every 5 frames
    FramePosition k;
    k.frame_index = i;
    k.keyframe_id = static_cast<long long>(i);
    k.timestamp = 0.1 * static_cast<double>(i);
    k.map_position = g.enu_frame.ToEnu(track[i]);
    keyframes.push_back(k);
  }
  OsmLandmarkOptions osm;
  osm.trajectory = track;
  const fs::path file = fs::path(maps) / "kitti_00.osm";
  std::vector<Landmark> catalogue = ReadLandmarks(file, osm);
  MakeLandmarkNamesUnique(catalogue);
  const std::vector<Street> streets = ReadStreetsOsm(file, osm);
  const TopologicalMap map =
      BuildTopologicalMap(keyframes, PlaceLandmarks(catalogue, g, keyframes), g, {}, streets);

  double length = 0, named = 0;
  for (const TopoEdge& e : map.edges) {
    length += e.length_m;
    if (!e.street.empty()) named += e.length_m;
    std::printf("edge %2d %2d-%2d %6.1f m  %s\n", e.id, e.from, e.to, e.length_m, e.street.c_str());
  }
  std::printf("%zu landmarks, %zu streets, %zu nodes, %zu edges; %.0f of %.0f m of edges on a named street\n",
              catalogue.size(), streets.size(), map.nodes.size(), map.edges.size(), named, length);
  std::vector<std::string> texts;
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"Kniebisstraße / Neckarstraße", "Enzstraße / Kinzigstraße"},
           {"Mainstraße / Schauinslandstraße", "Feldbergplatz / Kandelstraße"}}) {
    const Route route = FindRoute(map, from, to);
    std::printf("%s -> %s:\n", from.c_str(), to.c_str());
    for (const RouteStep& s : route.steps) {
      std::printf("  %s\n", s.text.c_str());
      texts.push_back(s.text);
    }
  }
  // Measured: 14 edges, 1198 m, every one on a named street; the routes turn into the streets they should.
  EXPECT_EQ(map.edges.size(), 14u);
  EXPECT_DOUBLE_EQ(named, length);
  EXPECT_THAT(texts, ::testing::Contains("Turn left into Enzstraße."));
  EXPECT_THAT(texts, ::testing::Contains("Turn left into Feldbergstraße."));
  EXPECT_THAT(texts, ::testing::Contains("Drive 30 m along Feldbergplatz to Feldbergplatz / Kandelstraße."));
}

}  // namespace
}  // namespace semslam
