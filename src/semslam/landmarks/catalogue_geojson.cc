// GeoJSON landmark catalogues (nlohmann_json stays in this file).

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "semslam/landmarks/catalogue.h"

namespace semslam {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// Lines (1-based) where the elements of the array under `key` in the root object start; empty when there is
// no such array. nlohmann does not report positions of values, so this structural scan finds them.
std::vector<int> ArrayElementLines(std::string_view text, std::string_view key) {
  enum class State { kScan, kMaybeKey, kExpectArray, kInArray };
  State state = State::kScan;
  std::vector<int> lines;
  int line = 1, depth = 0, array_depth = -1;
  bool in_string = false, escaped = false, expect_element = false;
  std::string current, last_string;
  for (const char c : text) {
    if (c == '\n') ++line;
    if (in_string) {
      if (escaped) {
        escaped = false;
        current.push_back(c);
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
        if (depth == 1 && state == State::kScan) {
          last_string = current;
          state = State::kMaybeKey;
        }
      } else {
        current.push_back(c);
      }
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r' || c == '\n') continue;
    if (state == State::kMaybeKey && c != ':') state = State::kScan;
    if (state == State::kInArray && expect_element && depth == array_depth && c != ']') {
      lines.push_back(line);
      expect_element = false;
    }
    switch (c) {
      case '"':
        in_string = true;
        current.clear();
        break;
      case '{':
      case '[':
        ++depth;
        if (state == State::kExpectArray) {
          if (c != '[') return {};
          state = State::kInArray;
          array_depth = depth;
          expect_element = true;
        }
        break;
      case '}':
      case ']':
        if (state == State::kInArray && depth == array_depth) return lines;
        --depth;
        break;
      case ':':
        if (state == State::kMaybeKey) state = last_string == key ? State::kExpectArray : State::kScan;
        break;
      case ',':
        if (state == State::kInArray && depth == array_depth) expect_element = true;
        break;
      default:
        if (state == State::kExpectArray) return {};
        break;
    }
  }
  return lines;
}

int LineOfByte(std::string_view text, size_t byte) {
  byte = std::min(byte, text.size());
  return 1 +
         static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(byte), '\n'));
}

std::string StringProperty(const json& properties, std::initializer_list<const char*> keys) {
  if (!properties.is_object()) return {};
  for (const char* key : keys) {
    const auto it = properties.find(key);
    if (it != properties.end() && it->is_string()) return it->get<std::string>();
  }
  return {};
}

std::vector<Landmark> LandmarksFromGeoJson(const json& root, std::string_view text, const fs::path& file);

}  // namespace

std::vector<Landmark> ReadLandmarksGeoJson(const fs::path& file) {
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw InputError(file, "cannot open the GeoJSON file");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  const std::string text = buffer.str();

  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(SourceLocation{file, LineOfByte(text, e.byte)}, "json", e.what());
  } catch (const json::exception& e) {  // a number out of range (1e309), ...
    throw InputError(SourceLocation{file, 0}, "json", e.what());
  }
  try {
    return LandmarksFromGeoJson(root, text, file);
  } catch (const json::exception& e) {  // a value of an unexpected type
    throw InputError(SourceLocation{file, 0}, "json", e.what());
  }
}

namespace {

std::vector<Landmark> LandmarksFromGeoJson(const json& root, std::string_view text, const fs::path& file) {
  if (!root.is_object()) throw InputError(SourceLocation{file, 1}, "type", "GeoJSON root must be an object");
  const std::string type = root.value("type", std::string());

  std::vector<json> features;
  std::vector<int> lines;
  if (type == "FeatureCollection") {
    const auto it = root.find("features");
    if (it == root.end() || !it->is_array()) {
      throw InputError(SourceLocation{file, 1}, "features", "a FeatureCollection needs a 'features' array");
    }
    features = it->get<std::vector<json>>();
    lines = ArrayElementLines(text, "features");
  } else if (type == "Feature") {
    features.push_back(root);
    lines.push_back(1);
  } else {
    throw InputError(SourceLocation{file, 1}, "type",
                     fmt::format("expected a FeatureCollection or a Feature, found '{}'", type));
  }

  std::vector<Landmark> landmarks;
  size_t ignored = 0;
  for (size_t i = 0; i < features.size(); ++i) {
    const SourceLocation where{file, i < lines.size() ? lines[i] : 0};
    const std::string field = type == "Feature" ? "" : fmt::format("features[{}].", i);
    const json& feature = features[i];
    if (!feature.is_object() || feature.value("type", std::string()) != "Feature") {
      throw InputError(where, field + "type", "expected an object of type 'Feature'");
    }
    const auto geometry = feature.find("geometry");
    if (geometry == feature.end() || geometry->is_null()) {
      ++ignored;
      continue;
    }
    if (!geometry->is_object()) throw InputError(where, field + "geometry", "expected an object");
    if (geometry->value("type", std::string()) != "Point") {
      ++ignored;
      continue;
    }
    const auto coordinates = geometry->find("coordinates");
    if (coordinates == geometry->end() || !coordinates->is_array() || coordinates->size() < 2 ||
        coordinates->size() > 3) {
      throw InputError(where, field + "geometry.coordinates", "a Point needs [lon, lat] or [lon, lat, alt]");
    }
    for (size_t k = 0; k < coordinates->size(); ++k) {
      const json& v = (*coordinates)[k];
      if (!v.is_number() || !std::isfinite(v.get<double>())) {
        throw InputError(where, fmt::format("{}geometry.coordinates[{}]", field, k),
                         "expected a finite number");
      }
    }
    Landmark landmark;
    landmark.source = where;
    landmark.position.longitude_deg = (*coordinates)[0].get<double>();
    landmark.position.latitude_deg = (*coordinates)[1].get<double>();
    if (std::abs(landmark.position.longitude_deg) > 180) {
      throw InputError(where, field + "geometry.coordinates[0]",
                       fmt::format("longitude {} out of [-180, 180]", landmark.position.longitude_deg));
    }
    if (std::abs(landmark.position.latitude_deg) > 90) {
      throw InputError(where, field + "geometry.coordinates[1]",
                       fmt::format("latitude {} out of [-90, 90] (GeoJSON order is [lon, lat])",
                                   landmark.position.latitude_deg));
    }
    if (coordinates->size() == 3) {
      landmark.position.altitude_m = (*coordinates)[2].get<double>();
      landmark.has_altitude = true;
    }
    const json properties = feature.value("properties", json::object());
    landmark.name = StringProperty(properties, {"name", "Name", "title", "label"});
    if (landmark.name.empty()) {
      throw InputError(where, field + "properties.name", "a landmark Point feature needs a non-empty name");
    }
    landmark.category = StringProperty(properties, {"category", "type", "class", "amenity", "building"});
    landmarks.push_back(std::move(landmark));
  }
  if (ignored > 0) spdlog::debug("{}: {} non-Point features ignored", file.string(), ignored);
  return landmarks;
}

}  // namespace

}  // namespace semslam
