// Street corners and streets of OpenStreetMap extracts.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include "semslam/geo/gps.h"
#include "semslam/landmarks/catalogue.h"
#include "support/test_support.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using testing::TempDir;

fs::path WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Around (49.0, 8.4); 0.0001 deg is 11.1 m north, 7.3 m east.
//  - Hauptstraße runs east along lat 49.0 (way 1001), then as a dual carriageway (1002 north, 1003 south,
//    one-way, 22 m apart) across Allee, itself a dual carriageway (1004 west, 1005 east, 22 m apart): the
//    four crossing nodes 111-114 are one corner. Node 103, where the three Hauptstraße ways meet, is none.
//  - Nebenstraße crosses Hauptstraße at node 102 (four arms) and becomes Parkweg at 202 (a name change where
//    an unnamed service way leaves: no corner).
//  - Ölweg leaves Hauptstraße at 107 (a T, three arms).
//  - Bogenweg, a crescent, leaves Parkweg at 204 and comes back at 205, 111 m north: two corners.
//  - An unnamed service way at 201, the building "Haus" sharing node 102, Randweg with a node missing from
//    the extract.
const char* kStreetsXml = R"(<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="test">
  <node id="101" lat="49.0000" lon="8.3980"/>
  <node id="107" lat="49.0000" lon="8.3990"/>
  <node id="102" lat="49.0000" lon="8.4000"/>
  <node id="103" lat="49.0000" lon="8.4020"/>
  <node id="111" lat="49.0001" lon="8.4030"/>
  <node id="112" lat="49.0001" lon="8.4033"/>
  <node id="113" lat="48.9999" lon="8.4030"/>
  <node id="114" lat="48.9999" lon="8.4033"/>
  <node id="106" lat="49.0000" lon="8.4045"/>
  <node id="301" lat="48.9990" lon="8.4030"/>
  <node id="302" lat="49.0010" lon="8.4030"/>
  <node id="303" lat="49.0010" lon="8.4033"/>
  <node id="304" lat="48.9990" lon="8.4033"/>
  <node id="201" lat="48.9990" lon="8.4000"/>
  <node id="202" lat="49.0010" lon="8.4000"/>
  <node id="204" lat="49.0015" lon="8.4000"/>
  <node id="205" lat="49.0025" lon="8.4000"/>
  <node id="203" lat="49.0030" lon="8.4000"/>
  <node id="501" lat="49.0015" lon="8.3990"/>
  <node id="502" lat="49.0025" lon="8.3990"/>
  <node id="401" lat="48.9990" lon="8.3990"/>
  <node id="601" lat="48.9985" lon="8.4005"/>
  <node id="602" lat="49.0010" lon="8.4010"/>
  <node id="701" lat="49.0010" lon="8.3960"/>
  <node id="703" lat="49.0010" lon="8.3970"/>
  <node id="704" lat="49.0010" lon="8.3975"/>
  <way id="1001"><nd ref="101"/><nd ref="107"/><nd ref="102"/><nd ref="103"/>
    <tag k="highway" v="secondary"/><tag k="name" v="Hauptstraße"/></way>
  <way id="1002"><nd ref="103"/><nd ref="111"/><nd ref="112"/><nd ref="106"/>
    <tag k="highway" v="secondary"/><tag k="oneway" v="yes"/><tag k="name" v="Hauptstraße"/></way>
  <way id="1003"><nd ref="106"/><nd ref="114"/><nd ref="113"/><nd ref="103"/>
    <tag k="highway" v="secondary"/><tag k="oneway" v="yes"/><tag k="name" v="Hauptstraße"/></way>
  <way id="1004"><nd ref="301"/><nd ref="113"/><nd ref="111"/><nd ref="302"/>
    <tag k="highway" v="primary"/><tag k="oneway" v="yes"/><tag k="name" v="Allee"/></way>
  <way id="1005"><nd ref="303"/><nd ref="112"/><nd ref="114"/><nd ref="304"/>
    <tag k="highway" v="primary"/><tag k="oneway" v="yes"/><tag k="name" v="Allee"/></way>
  <way id="1006"><nd ref="201"/><nd ref="102"/><nd ref="202"/>
    <tag k="highway" v="residential"/><tag k="name" v="Nebenstraße"/></way>
  <way id="1007"><nd ref="202"/><nd ref="204"/><nd ref="205"/><nd ref="203"/>
    <tag k="highway" v="residential"/><tag k="name" v="Parkweg"/></way>
  <way id="1008"><nd ref="204"/><nd ref="501"/><nd ref="502"/><nd ref="205"/>
    <tag k="highway" v="residential"/><tag k="name" v="Bogenweg"/></way>
  <way id="1009"><nd ref="107"/><nd ref="401"/>
    <tag k="highway" v="residential"/><tag k="name" v="Ölweg"/></way>
  <way id="1010"><nd ref="201"/><nd ref="601"/><tag k="highway" v="service"/></way>
  <way id="1011"><nd ref="202"/><nd ref="602"/><tag k="highway" v="service"/></way>
  <way id="1012"><nd ref="102"/><nd ref="601"/><nd ref="201"/><nd ref="102"/>
    <tag k="building" v="yes"/><tag k="name" v="Haus"/></way>
  <way id="1013"><nd ref="701"/><nd ref="702"/><nd ref="703"/><nd ref="704"/>
    <tag k="highway" v="track"/><tag k="name" v="Randweg"/></way>
</osm>
)";

std::vector<std::string> Names(const std::vector<Landmark>& landmarks) {
  std::vector<std::string> names;
  for (const Landmark& l : landmarks) names.push_back(l.name);
  return names;
}

std::vector<Landmark> Corners(const std::vector<Landmark>& landmarks) {
  std::vector<Landmark> corners;
  for (const Landmark& l : landmarks) {
    if (l.category == kCornerCategory) corners.push_back(l);
  }
  return corners;
}

TEST(OsmCorners, JunctionsOfNamedStreets) {
  TempDir dir;
  const fs::path file = WriteText(dir / "streets.osm", kStreetsXml);
  const std::vector<Landmark> all = ReadLandmarks(file);
  // The building first (landmarks in file order), then the corners by name (byte order: "Ö" after "H").
  ASSERT_EQ(all.size(), 6u);
  EXPECT_EQ(all[0].name, "Haus");
  const std::vector<Landmark> corners = Corners(all);
  EXPECT_THAT(Names(corners), ElementsAre("Allee / Hauptstraße", "Bogenweg / Parkweg", "Bogenweg / Parkweg",
                                          "Hauptstraße / Nebenstraße", "Hauptstraße / Ölweg"));
  // The dual carriageways' four crossing nodes, merged at their mean.
  EXPECT_NEAR(corners[0].position.latitude_deg, 49.0, 1e-7);
  EXPECT_NEAR(corners[0].position.longitude_deg, 8.40315, 1e-7);
  EXPECT_FALSE(corners[0].has_altitude);
  EXPECT_THAT(corners[0].source.file.string(), ::testing::EndsWith("streets.osm#node/111"));
  // The crescent's two ends, 111 m apart, stay two corners.
  EXPECT_NEAR(corners[1].position.latitude_deg, 49.0015, 1e-7);
  EXPECT_NEAR(corners[2].position.latitude_deg, 49.0025, 1e-7);
  EXPECT_NEAR(corners[3].position.longitude_deg, 8.4, 1e-7);    // node 102
  EXPECT_NEAR(corners[4].position.longitude_deg, 8.399, 1e-7);  // node 107

  // Merging: the carriageways are 22.2 m (north-south) and 21.9 m (east-west) apart.
  OsmLandmarkOptions options;
  options.corner_merge_m = 20.0;
  EXPECT_EQ(Corners(ReadLandmarksOsm(file, options)).size(), 5u + 3u);
  options.corner_merge_m = 23.0;
  EXPECT_EQ(Corners(ReadLandmarksOsm(file, options)).size(), 5u);
  options.corner_merge_m = 120.0;  // now the crescent's ends too
  EXPECT_EQ(Corners(ReadLandmarksOsm(file, options)).size(), 4u);

  options = {};
  options.include_corners = false;
  EXPECT_THAT(Names(ReadLandmarksOsm(file, options)), ElementsAre("Haus"));
  options.corner_radius_m = 0;
  EXPECT_THROW(ReadLandmarksOsm(file, options), InvalidArgument);
}

TEST(OsmCorners, OwnRadiusAroundTheTrajectory) {
  TempDir dir;
  const fs::path file = WriteText(dir / "streets.osm", kStreetsXml);
  OsmLandmarkOptions options;
  // Along Hauptstraße, 5 m south of its centre line.
  options.trajectory = {Wgs84{48.999955, 8.3970, 0}, Wgs84{48.999955, 8.4050, 0}};
  // The corners on the way (5 m); Bogenweg / Parkweg (172 m, 283 m) are not; the building (its centroid
  // 87 m off) is within radius_m.
  EXPECT_THAT(Names(ReadLandmarksOsm(file, options)),
              ElementsAre("Haus", "Allee / Hauptstraße", "Hauptstraße / Nebenstraße", "Hauptstraße / Ölweg"));
  options.corner_radius_m = 4.0;
  EXPECT_THAT(Names(ReadLandmarksOsm(file, options)), ElementsAre("Haus"));
  options.corner_radius_m = 200.0;
  EXPECT_EQ(Corners(ReadLandmarksOsm(file, options)).size(), 4u);

  // Read first, limited later: the same, each kind with its radius.
  OsmLandmarkOptions unlimited;
  const std::vector<Landmark> all = ReadLandmarksOsm(file, unlimited);
  options.corner_radius_m = 25.0;
  EXPECT_EQ(Names(KeepNearTrajectory(all, options)), Names(ReadLandmarksOsm(file, options)));
  options.include_corners = false;
  EXPECT_THAT(Names(KeepNearTrajectory(all, options)), ElementsAre("Haus"));
}

TEST(OsmStreets, NamedHighwaysAsPolylines) {
  TempDir dir;
  const fs::path file = WriteText(dir / "streets.osm", kStreetsXml);
  const std::vector<Street> streets = ReadStreetsOsm(file);
  std::vector<std::string> names;
  for (const Street& s : streets) names.push_back(s.name);
  // Unnamed service ways and the building are not streets; Randweg's node 702 is not in the extract, so only
  // its part after it is (the part before is a single node).
  EXPECT_THAT(names, ElementsAre("Hauptstraße", "Hauptstraße", "Hauptstraße", "Allee", "Allee", "Nebenstraße",
                                 "Parkweg", "Bogenweg", "Ölweg", "Randweg"));
  ASSERT_EQ(streets[0].polyline.size(), 4u);
  EXPECT_EQ(streets[0].highway, "secondary");
  EXPECT_NEAR(streets[0].polyline[1].longitude_deg, 8.399, 1e-7);
  EXPECT_THAT(streets[0].source.file.string(), ::testing::EndsWith("#way/1001"));
  ASSERT_EQ(streets.back().polyline.size(), 2u);
  EXPECT_NEAR(streets.back().polyline[0].longitude_deg, 8.397, 1e-7);

  // Near a trajectory: a street counts when any point of it (not only a node) is within radius_m.
  OsmLandmarkOptions options;
  options.trajectory = {Wgs84{49.0020, 8.4010, 0}};
  // Parkweg passes 73 m west (its nearest node 204 is 92 m away); Bogenweg's nearest points (its ends) are 92
  // m away, Nebenstraße's end 202 133 m.
  options.radius_m = 80.0;
  names.clear();
  for (const Street& s : ReadStreetsOsm(file, options)) names.push_back(s.name);
  EXPECT_THAT(names, ElementsAre("Parkweg"));
}

// Drive 0005 of KITTI raw (Karlsruhe Oststadt) and its OpenStreetMap extract: the corners on the drive.
TEST(OsmCorners, KittiRawDrive0005) {
  SEMSLAM_REQUIRE_SHARED_DATA(osm_dir, "kitti_raw_2011_09_26_drive_0005_osm");
  SEMSLAM_REQUIRE_SHARED_DATA(drive, "kitti_raw_2011_09_26_drive_0005/2011_09_26/2011_09_26_drive_0005_sync");
  const GpsLog log = ReadGps(drive / "oxts");
  OsmLandmarkOptions options;
  for (const GpsFix& fix : log.fixes) options.trajectory.push_back(fix.position);
  const fs::path file = osm_dir / "2011_09_26_drive_0005_sync.osm";
  const std::vector<Landmark> landmarks = ReadLandmarks(file, options);
  // The 25 named shops, amenities and offices of SOURCE.md (and 12 named buildings and others) as before.
  const auto shops = std::count_if(landmarks.begin(), landmarks.end(), [](const Landmark& l) {
    return l.category.rfind("shop=", 0) == 0 || l.category.rfind("amenity=", 0) == 0 ||
           l.category.rfind("office=", 0) == 0;
  });
  EXPECT_EQ(shops, 25);
  EXPECT_EQ(landmarks.size() - Corners(landmarks).size(), 37u);
  // The extract has 8 corners (Hölderlinstraße becoming Emil-Gött-Straße is none); 3 are on the drive, within
  // 1 m, 1 m and 4 m of it; the next are 44 m away. Karl-Wilhelm-Straße, a dual carriageway, meets the square
  // Karl-Wilhelm-Platz at two nodes 12.6 m apart: one corner.
  const std::vector<Landmark> corners = Corners(landmarks);
  EXPECT_THAT(Names(corners), ElementsAre("Georg-Friedrich-Straße / Karl-Wilhelm-Platz",
                                          "Georg-Friedrich-Straße / Rintheimer Straße",
                                          "Karl-Wilhelm-Platz / Karl-Wilhelm-Straße"));
  options.trajectory.clear();
  EXPECT_EQ(Corners(ReadLandmarks(file, options)).size(), 8u);
  options.corner_merge_m = 10.0;
  EXPECT_EQ(Corners(ReadLandmarks(file, options)).size(), 10u);  // and Haid-und-Neu-Straße's two nodes
}

// KITTI odometry sequence 00 (Karlsruhe), whose extract has hardly a named place: the corners of the part
// driven (frames 0-1699). The extract and the RTK GPS track (KML) are not in ../shared/data; run by hand with
// SEMSLAM_OSM_MAPS=DIR holding kitti_00.osm and RTK_GPS_kitti_00.kml.
TEST(OsmCorners, KittiOdometry00ByHand) {
  const char* maps = std::getenv("SEMSLAM_OSM_MAPS");
  if (maps == nullptr) GTEST_SKIP() << "set SEMSLAM_OSM_MAPS to the folder of kitti_00.osm";
  std::ifstream kml(fs::path(maps) / "RTK_GPS_kitti_00.kml");
  std::stringstream text;
  text << kml.rdbuf();
  const std::string k = text.str();
  const size_t begin = k.find("<coordinates>"), end = k.find("</coordinates>");
  ASSERT_NE(begin, std::string::npos);
  std::istringstream coordinates(k.substr(begin + 13, end - begin - 13));
  std::vector<Wgs84> track;
  for (std::string point; coordinates >> point && track.size() < 1700;) {
    double lon = 0, lat = 0, alt = 0;
    ASSERT_EQ(std::sscanf(point.c_str(), "%lf,%lf,%lf", &lon, &lat, &alt), 3) << point;
    track.push_back(Wgs84{lat, lon, alt});
  }
  ASSERT_EQ(track.size(), 1700u);
  OsmLandmarkOptions options;
  options.trajectory = track;
  const std::vector<Landmark> corners = Corners(ReadLandmarks(fs::path(maps) / "kitti_00.osm", options));
  const EnuFrame frame(track.front());
  for (const Landmark& c : corners) {
    const Eigen::Vector2d p = frame.ToEnu(c.position).head<2>();
    size_t nearest = 0;
    double d = std::numeric_limits<double>::infinity();
    for (size_t i = 0; i < track.size(); ++i) {
      const double di = (frame.ToEnu(track[i]).head<2>() - p).norm();
      if (di < d) {
        d = di;
        nearest = i;
      }
    }
    std::printf("%-45s %.7f %.7f frame %4zu %5.1f m  %s\n", c.name.c_str(), c.position.latitude_deg,
                c.position.longitude_deg, nearest, d, c.source.file.filename().string().c_str());
  }
  EXPECT_EQ(corners.size(), 13u);
}

}  // namespace
}  // namespace semslam
