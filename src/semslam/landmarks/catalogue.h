#pragma once
// Catalogues of named real-world landmarks (paper §III-D.1): CSV, GeoJSON Point features, and the named nodes
// and ways of an OpenStreetMap extract (.osm XML, optionally .gz/.bz2, and .osm.pbf, through libosmium).
// Malformed catalogues throw InputError naming file, line and field.

#include <filesystem>
#include <string>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/geo/wgs84.h"

namespace semslam {

struct Landmark {
  std::string name;
  Wgs84 position;  // altitude meaningful only when has_altitude
  bool has_altitude = false;
  std::string category;   // free text ("building", "amenity=cafe"); may be empty
  SourceLocation source;  // where it was read
};

// CSV `name,lat,lon[,alt,category]`. An optional header names the columns (name|title|label, lat|latitude,
// lon|lng|longitude, alt|altitude|height|elevation, category|type|class|kind) in any order; fields may be
// quoted ("Smith, Jones & Co"). Blank lines and lines starting with '#' are ignored.
std::vector<Landmark> ReadLandmarksCsv(const std::filesystem::path& file);

// GeoJSON: a FeatureCollection (or a single Feature) of Point features with [lon, lat(, alt)] coordinates;
// the name from properties.name (or title/label), the category from properties.category (or type/amenity).
// Features of other geometry types are ignored.
std::vector<Landmark> ReadLandmarksGeoJson(const std::filesystem::path& file);

struct OsmLandmarkOptions {
  // Keep only features within radius_m (horizontal) of this trajectory; empty: keep all.
  std::vector<Wgs84> trajectory;
  double radius_m = 150.0;
  // Named ways that are streets (highway=*) are not landmarks unless asked.
  bool include_streets = false;
  // Named nodes with no tag other than name-like ones (name, name:xx, alt_name, ...) are kept too.
  bool include_untagged_nodes = false;

  void Check() const;
};

// Named nodes, and named ways at their centroid (the mean of their node locations).
std::vector<Landmark> ReadLandmarksOsm(const std::filesystem::path& file,
                                       const OsmLandmarkOptions& options = {});

// The landmarks ReadLandmarksOsm would keep for `options` (within radius_m of the trajectory; all when it is
// empty), for a catalogue read before the trajectory was known.
std::vector<Landmark> KeepNearTrajectory(std::vector<Landmark> landmarks, const OsmLandmarkOptions& options);

// Whether ReadLandmarks reads `file` as OpenStreetMap (the only format limited to the trajectory).
bool IsOsmCatalogue(const std::filesystem::path& file);

// By extension: .csv; .geojson/.json; .osm, .osm.gz, .osm.bz2, .pbf, .osm.pbf.
std::vector<Landmark> ReadLandmarks(const std::filesystem::path& file,
                                    const OsmLandmarkOptions& osm_options = {});

// Names made unique ("Cafe", "Cafe (2)", ...), so that a route can name them.
void MakeLandmarkNamesUnique(std::vector<Landmark>& landmarks);

}  // namespace semslam
