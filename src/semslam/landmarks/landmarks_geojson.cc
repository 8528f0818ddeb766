// landmarks.geojson (nlohmann_json stays in writer/reader files).

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "semslam/core/atomic_file.h"
#include "semslam/landmarks/landmark_map.h"

namespace semslam {

using nlohmann::json;

void WriteLandmarksGeoJson(const std::filesystem::path& path, const std::vector<PlacedLandmark>& landmarks,
                           const FramePositions& keyframes, double sigma_m) {
  json features = json::array();
  for (const PlacedLandmark& p : landmarks) {
    json coordinates = {p.landmark.position.longitude_deg, p.landmark.position.latitude_deg};
    if (p.landmark.has_altitude) coordinates.push_back(p.landmark.position.altitude_m);
    json properties = {
        {"name", p.landmark.name},
        {"category", p.landmark.category},
        {"map_xyz", {p.map_position.x(), p.map_position.y(), p.map_position.z()}},
        {"enu", {p.enu.x(), p.enu.y(), p.enu.z()}},
        {"sigma_m", sigma_m},
    };
    if (p.nearest_keyframe >= 0 && static_cast<size_t>(p.nearest_keyframe) < keyframes.size()) {
      const FramePosition& k = keyframes[static_cast<size_t>(p.nearest_keyframe)];
      properties["nearest_keyframe"] = {{"index", p.nearest_keyframe},
                                        {"keyframe_id", k.keyframe_id},
                                        {"frame_index", k.frame_index},
                                        {"timestamp", k.timestamp},
                                        {"distance_m", p.keyframe_distance_m}};
      properties["membership"] = p.keyframe_membership.value;
      properties["membership_pdf"] = p.keyframe_membership.pdf;
    } else {
      properties["nearest_keyframe"] = nullptr;
      properties["membership"] = 0.0;
      properties["membership_pdf"] = 0.0;
    }
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "Point"}, {"coordinates", coordinates}}},
                        {"properties", properties}});
  }
  const json root = {{"type", "FeatureCollection"}, {"features", features}};
  WriteFileAtomically(path, root.dump(1) + "\n");
}

namespace {

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

std::string PlacedLandmarksToJson(const std::vector<PlacedLandmark>& landmarks) {
  json list = json::array();
  for (const PlacedLandmark& p : landmarks) {
    list.push_back({{"name", p.landmark.name},
                    {"category", p.landmark.category},
                    {"lat", p.landmark.position.latitude_deg},
                    {"lon", p.landmark.position.longitude_deg},
                    {"alt", p.landmark.position.altitude_m},
                    {"has_altitude", p.landmark.has_altitude},
                    {"enu", Vec(p.enu)},
                    {"map_xyz", Vec(p.map_position)},
                    {"nearest_keyframe", p.nearest_keyframe},
                    {"keyframe_distance_m", p.keyframe_distance_m},
                    {"membership", p.keyframe_membership.value},
                    {"membership_pdf", p.keyframe_membership.pdf}});
  }
  return list.dump();
}

std::vector<PlacedLandmark> PlacedLandmarksFromJson(const std::string& text,
                                                    const std::filesystem::path& source) {
  const auto fail = [&](const std::string& field, const std::string& message) {
    throw InputError(SourceLocation{source, 0}, field, message);
  };
  json list;
  try {
    list = json::parse(text);
  } catch (const json::parse_error& e) {
    fail("json", e.what());
  }
  if (!list.is_array()) fail("landmarks", "expected an array");
  std::vector<PlacedLandmark> out;
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string p = fmt::format("landmarks[{}]", i);
    const json& j = list[i];
    const auto member = [&](const char* key) -> const json& {
      if (!j.is_object() || !j.contains(key)) fail(p + "." + key, "missing");
      return j.at(key);
    };
    const auto number = [&](const char* key) {
      const json& v = member(key);
      if (!v.is_number() || !std::isfinite(v.get<double>())) fail(p + "." + key, "expected a finite number");
      return v.get<double>();
    };
    const auto vec = [&](const char* key) {
      const json& v = member(key);
      if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
        fail(p + "." + key, "expected [x, y, z]");
      }
      return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
    };
    PlacedLandmark l;
    if (!member("name").is_string() || member("name").get<std::string>().empty())
      fail(p + ".name", "expected a name");
    l.landmark.name = member("name").get<std::string>();
    if (!member("category").is_string()) fail(p + ".category", "expected a string");
    l.landmark.category = member("category").get<std::string>();
    l.landmark.position = Wgs84{number("lat"), number("lon"), number("alt")};
    if (!l.landmark.position.IsValid()) fail(p, "not a valid WGS84 position");
    if (!member("has_altitude").is_boolean()) fail(p + ".has_altitude", "expected true or false");
    l.landmark.has_altitude = member("has_altitude").get<bool>();
    l.landmark.source = SourceLocation{source, 0};
    l.enu = vec("enu");
    l.map_position = vec("map_xyz");
    if (!member("nearest_keyframe").is_number_integer()) fail(p + ".nearest_keyframe", "expected an integer");
    l.nearest_keyframe = member("nearest_keyframe").get<int>();
    l.keyframe_distance_m = number("keyframe_distance_m");
    l.keyframe_membership = Membership{number("membership"), number("membership_pdf")};
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace semslam
