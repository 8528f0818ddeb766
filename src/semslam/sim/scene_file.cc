#include "semslam/sim/scene_file.h"

#include <fmt/format.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "semslam/core/error.h"

namespace semslam::sim {
namespace {

using Json = nlohmann::json;

template <typename T>
void Get(const Json& object, const char* section, const char* key, const std::filesystem::path& file,
         T* value) {
  try {
    *value = object.at(section).at(key).get<T>();
  } catch (const Json::exception& e) {
    throw InputError(SourceLocation{file, 0}, fmt::format("options.{}.{}", section, key), e.what());
  }
}

}  // namespace

SynthOptions ReadSceneOptions(const std::filesystem::path& scene_json) {
  std::ifstream in(scene_json);
  if (!in) throw InputError(scene_json, "cannot open the scene file");
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::parse_error& e) {
    throw InputError(scene_json, fmt::format("not valid JSON: {}", e.what()));
  }
  if (!j.contains("options") || !j["options"].is_object())
    throw InputError(scene_json, "no 'options' object");
  const Json& o = j["options"];
  SynthOptions options;
  try {
    options = PresetOptions(o.value("preset", std::string("default")));
  } catch (const InvalidArgument& e) {
    throw InputError(SourceLocation{scene_json, 0}, "options.preset", e.what());
  }
  Get(o, "city", "seed", scene_json, &options.city.seed);
  Get(o, "city", "traffic_seed", scene_json, &options.city.traffic_seed);
  Get(o, "city", "blocks_x", scene_json, &options.city.blocks_x);
  Get(o, "city", "blocks_y", scene_json, &options.city.blocks_y);
  Get(o, "city", "min_block", scene_json, &options.city.min_block);
  Get(o, "city", "max_block", scene_json, &options.city.max_block);
  Get(o, "city", "parked_car_density", scene_json, &options.city.parked_car_density);
  Get(o, "city", "person_density", scene_json, &options.city.person_density);
  Get(o, "city", "bicycle_density", scene_json, &options.city.bicycle_density);
  Get(o, "city", "tree_density", scene_json, &options.city.tree_density);
  Get(o, "city", "park_blocks", scene_json, &options.city.park_blocks);
  Get(o, "route", "frames", scene_json, &options.route.frames);
  Get(o, "route", "rate_hz", scene_json, &options.route.rate_hz);
  Get(o, "route", "min_speed", scene_json, &options.route.min_speed);
  Get(o, "route", "max_speed", scene_json, &options.route.max_speed);
  Get(o, "route", "camera_height", scene_json, &options.route.camera_height);
  Get(o, "route", "reverse", scene_json, &options.route.reverse);
  Get(o, "route", "seed", scene_json, &options.route.seed);
  if (o.contains("route") && o["route"].is_object() && o["route"].contains("route_seed"))
    Get(o, "route", "route_seed", scene_json, &options.route.route_seed);
  Get(o, "camera", "width", scene_json, &options.camera.width);
  Get(o, "camera", "height", scene_json, &options.camera.height);
  Get(o, "camera", "focal", scene_json, &options.camera.focal);
  Get(o, "camera", "baseline", scene_json, &options.camera.baseline);
  try {
    options.gps.origin.latitude_deg = j.at("origin").at("latitude").get<double>();
    options.gps.origin.longitude_deg = j.at("origin").at("longitude").get<double>();
    options.gps.origin.altitude_m = j.at("origin").at("altitude").get<double>();
    options.gps.start_epoch = j.at("start_epoch").get<double>();
  } catch (const Json::exception& e) {
    throw InputError(SourceLocation{scene_json, 0}, "origin", e.what());
  }
  try {
    options.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(scene_json, e.what());
  }
  return options;
}

std::optional<std::filesystem::path> FindSceneJson(const std::filesystem::path& sequence_dir) {
  std::filesystem::path dir = std::filesystem::absolute(sequence_dir).lexically_normal();
  if (dir.filename().empty()) dir = dir.parent_path();  // a trailing separator
  for (int up = 0; up < 3 && !dir.empty(); ++up) {
    if (std::filesystem::is_regular_file(dir / "scene.json")) return dir / "scene.json";
    if (dir == dir.parent_path()) break;
    dir = dir.parent_path();
  }
  return std::nullopt;
}

}  // namespace semslam::sim
