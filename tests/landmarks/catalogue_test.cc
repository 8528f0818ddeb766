#include "semslam/landmarks/catalogue.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <osmium/builder/attr.hpp>
#include <osmium/io/any_output.hpp>
#include <osmium/memory/buffer.hpp>

#include "support/test_support.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using testing::TempDir;

fs::path WriteText(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// Expects `read` to throw an InputError whose message contains `what`.
template <typename Read>
void ExpectInputError(Read read, const std::string& what) {
  try {
    read();
    ADD_FAILURE() << "no error, expected one containing: " << what;
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(what));
  }
}

TEST(LandmarksCsv, PlainAndWithHeader) {
  TempDir dir;
  const auto plain = WriteText(dir / "a.csv",
                               "# name,lat,lon,alt,category\n"
                               "Town Hall,49.01,8.40\n"
                               "\n"
                               "\"Smith, Jones & Co\",49.02,8.41,120.5,shop\n"
                               "Tower,49.03,8.42,,\n");
  const auto l = ReadLandmarksCsv(plain);
  ASSERT_EQ(l.size(), 3u);
  EXPECT_EQ(l[0].name, "Town Hall");
  EXPECT_DOUBLE_EQ(l[0].position.latitude_deg, 49.01);
  EXPECT_DOUBLE_EQ(l[0].position.longitude_deg, 8.40);
  EXPECT_FALSE(l[0].has_altitude);
  EXPECT_EQ(l[0].source.line, 2);
  EXPECT_EQ(l[1].name, "Smith, Jones & Co");
  EXPECT_TRUE(l[1].has_altitude);
  EXPECT_DOUBLE_EQ(l[1].position.altitude_m, 120.5);
  EXPECT_EQ(l[1].category, "shop");
  EXPECT_FALSE(l[2].has_altitude);
  EXPECT_EQ(l[2].category, "");

  const auto header =
      WriteText(dir / "b.csv", "Longitude,Latitude,Title,Kind,notes\n8.5,49.5,Museum,museum,x\n");
  const auto h = ReadLandmarksCsv(header);
  ASSERT_EQ(h.size(), 1u);
  EXPECT_EQ(h[0].name, "Museum");
  EXPECT_DOUBLE_EQ(h[0].position.latitude_deg, 49.5);
  EXPECT_DOUBLE_EQ(h[0].position.longitude_deg, 8.5);
  EXPECT_EQ(h[0].category, "museum");
  EXPECT_EQ(ReadLandmarks(header).size(), 1u);  // dispatch by extension
}

TEST(LandmarksCsv, MalformedFilesNameFileLineAndField) {
  TempDir dir;
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "lat.csv", "A,49,8\nB,forty,8\n")); },
                   "lat.csv:2: field 'lat'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "range.csv", "A,95,8\n")); },
                   "range.csv:1: field 'lat'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "lon.csv", "A,49,-190\n")); },
                   "lon.csv:1: field 'lon'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "nan.csv", "A,nan,8\n")); },
                   "nan.csv:1: field 'lat'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "cols.csv", "A,49\n")); },
                   "cols.csv:1: field 'columns'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "cols2.csv", "A,49,8\nB,49,8,1,c,extra\n")); },
                   "cols2.csv:2: field 'columns'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "name.csv", "A,49,8\n\"\",49,8\n")); },
                   "name.csv:2: field 'name'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "head.csv", "title,latitude,height\nA,49,8\n")); },
                   "head.csv:1: field 'header'");
  ExpectInputError([&] { ReadLandmarksCsv(WriteText(dir / "quote.csv", "\"A,49,8\n")); }, "quote.csv:1");
  ExpectInputError([&] { ReadLandmarksCsv(dir / "missing.csv"); }, "missing.csv");
  ExpectInputError([&] { ReadLandmarks(WriteText(dir / "a.kml", "")); }, "unknown landmark catalogue format");
}

TEST(LandmarksGeoJson, PointsOfACollectionAndASingleFeature) {
  TempDir dir;
  const auto file = WriteText(dir / "a.geojson", R"({
  "type": "FeatureCollection",
  "features": [
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.40, 49.01]},
     "properties": {"name": "Town Hall", "category": "townhall"}},
    {"type": "Feature", "geometry": {"type": "LineString", "coordinates": [[8.4, 49.0], [8.5, 49.1]]},
     "properties": {"name": "Main Street"}},
    {"type": "Feature", "geometry": null, "properties": {"name": "Nowhere"}},
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.41, 49.02, 130.0]},
     "properties": {"title": "Tower", "amenity": "tower"}}
  ]
})");
  const auto l = ReadLandmarksGeoJson(file);
  ASSERT_EQ(l.size(), 2u);
  EXPECT_EQ(l[0].name, "Town Hall");
  EXPECT_DOUBLE_EQ(l[0].position.latitude_deg, 49.01);
  EXPECT_DOUBLE_EQ(l[0].position.longitude_deg, 8.40);
  EXPECT_EQ(l[0].category, "townhall");
  EXPECT_EQ(l[0].source.line, 4);
  EXPECT_EQ(l[1].name, "Tower");
  EXPECT_TRUE(l[1].has_altitude);
  EXPECT_DOUBLE_EQ(l[1].position.altitude_m, 130.0);
  EXPECT_EQ(l[1].category, "tower");
  EXPECT_EQ(l[1].source.line, 9);

  const auto single =
      WriteText(dir / "b.json", R"({"type":"Feature","geometry":{"type":"Point","coordinates":[8.4,49.0]},)"
                                R"("properties":{"name":"Solo"}})");
  ASSERT_EQ(ReadLandmarks(single).size(), 1u);
}

TEST(LandmarksGeoJson, MalformedFilesNameFileLineAndField) {
  TempDir dir;
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "syntax.geojson", "{\n\"type\": \n}")); },
                   "syntax.geojson:3: field 'json'");
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "root.geojson", "[1, 2]")); }, "field 'type'");
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "kind.geojson", R"({"type": "Topology"})")); },
                   "expected a FeatureCollection or a Feature");
  ExpectInputError(
      [&] { ReadLandmarksGeoJson(WriteText(dir / "nofeat.geojson", R"({"type": "FeatureCollection"})")); },
      "field 'features'");
  const std::string swapped = R"({"type": "FeatureCollection", "features": [
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.4, 49.0]}, "properties": {"name": "A"}},
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [49.0, 108.4]}, "properties": {"name": "B"}}
  ]})";
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "swapped.geojson", swapped)); },
                   "swapped.geojson:3: field 'features[1].geometry.coordinates[1]'");
  const std::string unnamed = R"({"type": "FeatureCollection", "features": [
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.4, 49.0]}, "properties": {}}]})";
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "unnamed.geojson", unnamed)); },
                   "unnamed.geojson:2: field 'features[0].properties.name'");
  const std::string text_coordinate = R"({"type": "FeatureCollection", "features": [
    {"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.4, "49"]}, "properties": {"name": "A"}}]})";
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "text.geojson", text_coordinate)); },
                   "field 'features[0].geometry.coordinates[1]'");
  const std::string short_point = R"({"type": "Feature", "geometry": {"type": "Point", "coordinates": [8.4]},
    "properties": {"name": "A"}})";
  ExpectInputError([&] { ReadLandmarksGeoJson(WriteText(dir / "short.geojson", short_point)); },
                   "field 'geometry.coordinates'");
}

// A small extract around (49.0, 8.4): a named cafe node, a named building way, a named street, an untagged
// named node, and a far-away museum.
const char* kOsmXml = R"(<?xml version="1.0" encoding="UTF-8"?>
<osm version="0.6" generator="test">
  <node id="1" lat="49.0000" lon="8.4000"><tag k="amenity" v="cafe"/><tag k="name" v="Cafe Central"/></node>
  <node id="2" lat="49.0010" lon="8.4010"/>
  <node id="3" lat="49.0010" lon="8.4020"/>
  <node id="4" lat="49.0020" lon="8.4020"/>
  <node id="5" lat="49.0020" lon="8.4010"/>
  <node id="6" lat="49.0000" lon="8.4100"/>
  <node id="7" lat="49.0005" lon="8.4005"><tag k="name" v="Just A Name"/></node>
  <node id="8" lat="49.1000" lon="8.5000"><tag k="tourism" v="museum"/><tag k="name" v="Far Museum"/></node>
  <way id="10"><nd ref="2"/><nd ref="3"/><nd ref="4"/><nd ref="5"/><nd ref="2"/>
    <tag k="building" v="yes"/><tag k="name" v="Old Library"/></way>
  <way id="11"><nd ref="1"/><nd ref="6"/><tag k="highway" v="residential"/><tag k="name" v="Main Street"/></way>
</osm>
)";

TEST(LandmarksOsm, NamedNodesAndWaysNearTheTrajectory) {
  TempDir dir;
  const auto file = WriteText(dir / "extract.osm", kOsmXml);
  auto all = ReadLandmarks(file);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].name, "Cafe Central");
  EXPECT_EQ(all[0].category, "amenity=cafe");
  EXPECT_DOUBLE_EQ(all[0].position.latitude_deg, 49.0);
  EXPECT_EQ(all[1].name, "Far Museum");
  EXPECT_EQ(all[2].name, "Old Library");
  EXPECT_EQ(all[2].category, "building=yes");
  // The centroid of the four distinct corners (the closing node counted once).
  EXPECT_NEAR(all[2].position.latitude_deg, 49.0015, 1e-9);
  EXPECT_NEAR(all[2].position.longitude_deg, 8.4015, 1e-9);
  EXPECT_THAT(all[2].source.file.string(), HasSubstr("#way/10"));

  OsmLandmarkOptions options;
  options.include_streets = true;
  options.include_untagged_nodes = true;
  options.trajectory = {Wgs84{49.001, 8.4, 0}, Wgs84{49.001, 8.402, 0}};  // about 146 m east
  options.radius_m = 300.0;
  const auto near = ReadLandmarksOsm(file, options);
  std::vector<std::string> names;
  for (const Landmark& l : near) names.push_back(l.name);
  // The cafe is 111 m from the trajectory, the library and the plain name 56 m, Main Street's centroid
  // (49.0, 8.405) 245 m, the museum 13 km.
  EXPECT_THAT(names,
              ::testing::UnorderedElementsAre("Cafe Central", "Just A Name", "Old Library", "Main Street"));
  options.radius_m = 150.0;
  names.clear();
  for (const Landmark& l : ReadLandmarksOsm(file, options)) names.push_back(l.name);
  EXPECT_THAT(names, ::testing::UnorderedElementsAre("Cafe Central", "Just A Name", "Old Library"));

  // Read first and limited later (as semslam run does, before the trajectory exists): the same landmarks.
  OsmLandmarkOptions unlimited = options;
  unlimited.trajectory.clear();
  names.clear();
  for (const Landmark& l : KeepNearTrajectory(ReadLandmarksOsm(file, unlimited), options))
    names.push_back(l.name);
  EXPECT_THAT(names, ::testing::UnorderedElementsAre("Cafe Central", "Just A Name", "Old Library"));
  EXPECT_TRUE(IsOsmCatalogue(file));
  EXPECT_FALSE(IsOsmCatalogue(dir / "catalogue.csv"));

  options.radius_m = -1;
  EXPECT_THROW(ReadLandmarksOsm(file, options), InvalidArgument);
  EXPECT_THROW(KeepNearTrajectory({}, options), InvalidArgument);
}

TEST(LandmarksOsm, ReadsPbf) {
  TempDir dir;
  const fs::path file = dir / "extract.osm.pbf";
  {
    using namespace osmium::builder::attr;  // NOLINT
    osmium::memory::Buffer buffer(4096, osmium::memory::Buffer::auto_grow::yes);
    osmium::builder::add_node(buffer, _id(1), _version(1), _location(8.4, 49.0), _tag("amenity", "cafe"),
                              _tag("name", "Cafe Central"));
    osmium::builder::add_node(buffer, _id(2), _version(1), _location(8.41, 49.01),
                              _tag("name:de", "Nur Name"));
    osmium::io::Writer writer(file.string());
    writer(std::move(buffer));
    writer.close();
  }
  const auto l = ReadLandmarks(file);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_EQ(l[0].name, "Cafe Central");
  EXPECT_NEAR(l[0].position.longitude_deg, 8.4, 1e-7);  // OSM stores 1e-7 degree fixed point
  EXPECT_NEAR(l[0].position.latitude_deg, 49.0, 1e-7);
}

TEST(LandmarksOsm, MalformedXmlNamesTheLine) {
  TempDir dir;
  const auto file = WriteText(
      dir / "bad.osm", "<?xml version=\"1.0\"?>\n<osm version=\"0.6\">\n<node id=\"1\" lat=\"49\"\n</osm>\n");
  ExpectInputError([&] { ReadLandmarksOsm(file); }, "bad.osm:");
  ExpectInputError([&] { ReadLandmarksOsm(dir / "missing.osm"); }, "missing.osm");
}

TEST(Landmarks, NamesMadeUnique) {
  std::vector<Landmark> l(4);
  l[0].name = "Cafe";
  l[1].name = "Cafe";
  l[2].name = "Cafe (2)";
  l[3].name = "Cafe";
  MakeLandmarkNamesUnique(l);
  EXPECT_EQ(l[0].name, "Cafe");
  EXPECT_EQ(l[1].name, "Cafe (3)");
  EXPECT_EQ(l[2].name, "Cafe (2)");
  EXPECT_EQ(l[3].name, "Cafe (4)");
}

}  // namespace
}  // namespace semslam
