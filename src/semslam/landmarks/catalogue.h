#pragma once
// Catalogues of named real-world landmarks (paper §III-D.1): CSV, GeoJSON Point features, and the named nodes
// and ways and the street corners of an OpenStreetMap extract (.osm XML, optionally .gz/.bz2, and .osm.pbf,
// through libosmium); and the named streets of an extract, for routes that name them.
// Malformed catalogues throw InputError naming file, line and field.

#include <filesystem>
#include <string>
#include <string_view>
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
  // Street corners (category kCornerCategory), where an extract has few named places to navigate by.
  bool include_corners = true;
  // Corners are kept within this of the trajectory, not radius_m: a corner the route goes through lies
  // within a junction's half-width (5-15 m) of the lane, plus GPS and map offsets; the corners of the next
  // parallel street (a block, 50 m or more, away) are not on the route and would only crowd it.
  double corner_radius_m = 25.0;
  // Junction nodes of the same streets closer than this (chained) are one corner: a dual carriageway
  // crossed, a corner drawn as several nodes, a one-way pair leaving a street (up to ~40 m apart); the two
  // ends of a crescent on one street lie farther apart and stay two.
  double corner_merge_m = 50.0;

  void Check() const;
};

// The category of street corners read from OpenStreetMap.
inline constexpr std::string_view kCornerCategory = "corner";

// Named nodes, and named ways at their centroid (the mean of their node locations); then, with
// include_corners, street corners: nodes shared by highway=* ways of two or more distinct `name`s where these
// named ways have three or more arms (a street that merely changes its name is not a corner, even where an
// unnamed way leaves there; unnamed ways neither name nor make corners). Named "A / B" (or "A / B / C"), the
// names in byte (UTF-8) order; corners with the same names whose nodes chain within corner_merge_m are merged
// into one at their nodes' mean. Corners follow the other landmarks, ordered by name and then by their lowest
// node id.
std::vector<Landmark> ReadLandmarksOsm(const std::filesystem::path& file,
                                       const OsmLandmarkOptions& options = {});

// The landmarks ReadLandmarksOsm would keep for `options` (within radius_m of the trajectory, corners within
// corner_radius_m; all when it is empty; no corners without include_corners), for a catalogue read before the
// trajectory was known.
std::vector<Landmark> KeepNearTrajectory(std::vector<Landmark> landmarks, const OsmLandmarkOptions& options);

// A named street of an OpenStreetMap extract: one highway=* way (or the part of it inside the extract).
struct Street {
  std::string name;
  std::string highway;          // the highway=* value ("residential", "primary", ...)
  std::vector<Wgs84> polyline;  // its nodes in order, at least two (altitude 0)
  SourceLocation source;        // FILE#way/ID
};

// The named highway=* ways with a point within radius_m of options.trajectory (all when it is empty), in file
// order; a way whose nodes leave the extract gives one Street per run of two or more nodes inside it.
std::vector<Street> ReadStreetsOsm(const std::filesystem::path& file, const OsmLandmarkOptions& options = {});

// Whether ReadLandmarks reads `file` as OpenStreetMap (the only format limited to the trajectory).
bool IsOsmCatalogue(const std::filesystem::path& file);

// By extension: .csv; .geojson/.json; .osm, .osm.gz, .osm.bz2, .pbf, .osm.pbf.
std::vector<Landmark> ReadLandmarks(const std::filesystem::path& file,
                                    const OsmLandmarkOptions& osm_options = {});

// Names made unique ("Cafe", "Cafe (2)", ...), so that a route can name them.
void MakeLandmarkNamesUnique(std::vector<Landmark>& landmarks);

}  // namespace semslam
