// CSV landmark catalogues, format dispatch, unique names.

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <set>

#include "semslam/core/text_reader.h"
#include "semslam/core/utf8.h"
#include "semslam/geo/csv.h"
#include "semslam/landmarks/catalogue.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

enum class Column { kName, kLat, kLon, kAlt, kCategory, kIgnored };

Column ColumnFromName(const std::string& raw) {
  static const std::map<std::string, Column> names = {
      {"name", Column::kName},      {"title", Column::kName},        {"label", Column::kName},
      {"lat", Column::kLat},        {"latitude", Column::kLat},      {"latdeg", Column::kLat},
      {"lon", Column::kLon},        {"lng", Column::kLon},           {"long", Column::kLon},
      {"longitude", Column::kLon},  {"londeg", Column::kLon},        {"alt", Column::kAlt},
      {"altitude", Column::kAlt},   {"height", Column::kAlt},        {"elevation", Column::kAlt},
      {"altm", Column::kAlt},       {"category", Column::kCategory}, {"type", Column::kCategory},
      {"class", Column::kCategory}, {"kind", Column::kCategory}};
  const auto it = names.find(NormalizeColumnName(raw));
  return it == names.end() ? Column::kIgnored : it->second;
}

bool LooksNumeric(std::string_view s) {
  s = Trim(s);
  if (s.empty()) return false;
  const char c = s.front();
  return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.';
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool EndsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::vector<Landmark> ReadLandmarksCsv(const fs::path& file) {
  TextReader reader(file);
  std::vector<Column> columns = {Column::kName, Column::kLat, Column::kLon, Column::kAlt, Column::kCategory};
  bool has_header = false, first_record = true;
  std::vector<Landmark> landmarks;
  while (const auto line = reader.NextLine()) {
    const std::string_view text = Trim(*line);
    if (text.empty() || text.front() == '#') continue;
    const SourceLocation where = reader.Where();
    const std::vector<std::string> fields = SplitCsvRecord(text, where);
    if (first_record) {
      first_record = false;
      // A header names at least one known column and has no number where the latitude goes ("A,nan,8" is a
      // record with a bad latitude, not a header).
      const bool names_a_column = std::any_of(fields.begin(), fields.end(), [](const std::string& f) {
        return ColumnFromName(f) != Column::kIgnored;
      });
      if (names_a_column && (fields.size() < 2 || !LooksNumeric(fields[1]))) {
        has_header = true;
        columns.clear();
        for (const std::string& name : fields) columns.push_back(ColumnFromName(name));
        for (const auto& [needed, label] : {std::pair{Column::kName, "name"}, std::pair{Column::kLat, "lat"},
                                            std::pair{Column::kLon, "lon"}}) {
          if (std::find(columns.begin(), columns.end(), needed) == columns.end()) {
            throw InputError(where, "header",
                             fmt::format("a landmark CSV header needs a '{}' column", label));
          }
        }
        continue;
      }
    }
    if (has_header ? fields.size() != columns.size() : (fields.size() < 3 || fields.size() > 5)) {
      throw InputError(
          where, "columns",
          has_header
              ? fmt::format("expected {} fields as in the header, found {}", columns.size(), fields.size())
              : fmt::format("expected name,lat,lon[,alt,category] (3 to 5 fields), found {}", fields.size()));
    }
    Landmark landmark;
    landmark.source = where;
    for (size_t i = 0; i < fields.size(); ++i) {
      const std::string& value = fields[i];
      switch (columns[i]) {
        case Column::kName:
          landmark.name = std::string(Trim(value));
          if (landmark.name.empty()) throw InputError(where, "name", "empty landmark name");
          RequireUtf8(landmark.name, where, "name");  // names go into GeoJSON, JSON and HTML outputs
          break;
        case Column::kLat:
          landmark.position.latitude_deg = ParseDouble(value, where, "lat");
          if (std::abs(landmark.position.latitude_deg) > 90) {
            throw InputError(where, "lat", fmt::format("latitude {} out of [-90, 90]", value));
          }
          break;
        case Column::kLon:
          landmark.position.longitude_deg = ParseDouble(value, where, "lon");
          if (std::abs(landmark.position.longitude_deg) > 180) {
            throw InputError(where, "lon", fmt::format("longitude {} out of [-180, 180]", value));
          }
          break;
        case Column::kAlt:
          if (!Trim(value).empty()) {
            landmark.position.altitude_m = ParseDouble(value, where, "alt");
            landmark.has_altitude = true;
          }
          break;
        case Column::kCategory:
          landmark.category = std::string(Trim(value));
          RequireUtf8(landmark.category, where, "category");
          break;
        case Column::kIgnored:
          break;
      }
    }
    landmarks.push_back(std::move(landmark));
  }
  return landmarks;
}

bool IsOsmCatalogue(const fs::path& file) {
  const std::string name = Lower(file.filename().string());
  return EndsWith(name, ".osm") || EndsWith(name, ".pbf") || EndsWith(name, ".osm.gz") ||
         EndsWith(name, ".osm.bz2") || EndsWith(name, ".osm.xml");
}

std::vector<Landmark> ReadLandmarks(const fs::path& file, const OsmLandmarkOptions& osm_options) {
  const std::string name = Lower(file.filename().string());
  if (EndsWith(name, ".csv") || EndsWith(name, ".txt")) return ReadLandmarksCsv(file);
  if (EndsWith(name, ".geojson") || EndsWith(name, ".json")) return ReadLandmarksGeoJson(file);
  if (IsOsmCatalogue(file)) {
    std::vector<Landmark> landmarks = ReadLandmarksOsm(file, osm_options);
    // OpenStreetMap text is UTF-8 by definition, but an extract can be damaged.
    for (const Landmark& landmark : landmarks) {
      RequireUtf8(landmark.name, landmark.source, "name");
      RequireUtf8(landmark.category, landmark.source, "category");
    }
    return landmarks;
  }
  throw InputError(
      file,
      "unknown landmark catalogue format (expected .csv, .geojson, .json, .osm, .osm.gz, .osm.bz2 or "
      ".osm.pbf)");
}

void MakeLandmarkNamesUnique(std::vector<Landmark>& landmarks) {
  std::set<std::string> used;
  std::map<std::string, int> count;
  for (const Landmark& l : landmarks) used.insert(l.name);
  std::set<std::string> seen;
  for (Landmark& l : landmarks) {
    if (seen.insert(l.name).second) continue;
    int& k = count[l.name];
    if (k == 0) k = 1;
    std::string candidate;
    do {
      candidate = fmt::format("{} ({})", l.name, ++k);
    } while (used.count(candidate) > 0);
    used.insert(candidate);
    seen.insert(candidate);
    l.name = candidate;
  }
}

}  // namespace semslam
