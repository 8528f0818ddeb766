// Georeference <-> JSON (nlohmann_json stays in this file).

#include "semslam/geo/georeference_json.h"

#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>

#include "semslam/core/error.h"

namespace semslam {

using nlohmann::json;

namespace {

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json SimJson(const Sim3d& s) {
  return {{"scale", s.scale},
          {"rotation_wxyz", {s.rotation.w(), s.rotation.x(), s.rotation.y(), s.rotation.z()}},
          {"translation", Vec(s.translation)}};
}

class Reader {
 public:
  explicit Reader(std::filesystem::path source) : source_(std::move(source)) {}
  [[noreturn]] void Fail(const std::string& field, const std::string& message) const {
    throw InputError(SourceLocation{source_, 0}, field, message);
  }
  const json& Member(const json& j, const char* key, const std::string& path) const {
    const std::string field = path.empty() ? key : path + "." + key;
    if (!j.is_object() || !j.contains(key)) Fail(field, "missing");
    return j.at(key);
  }
  double Number(const json& j, const std::string& field) const {
    if (!j.is_number() || !std::isfinite(j.get<double>())) Fail(field, "expected a finite number");
    return j.get<double>();
  }
  Eigen::Vector3d Vector(const json& j, const std::string& field) const {
    if (!j.is_array() || j.size() != 3) Fail(field, "expected [x, y, z]");
    return {Number(j[0], field + "[0]"), Number(j[1], field + "[1]"), Number(j[2], field + "[2]")};
  }
  Sim3d Sim(const json& j, const std::string& path) const {
    const double scale = Number(Member(j, "scale", path), path + ".scale");
    if (!(scale > 0)) Fail(path + ".scale", "must be positive");
    const json& q = Member(j, "rotation_wxyz", path);
    if (!q.is_array() || q.size() != 4) Fail(path + ".rotation_wxyz", "expected 4 numbers");
    Eigen::Vector4d wxyz;
    for (int i = 0; i < 4; ++i)
      wxyz[i] = Number(q[static_cast<size_t>(i)], fmt::format("{}.rotation_wxyz[{}]", path, i));
    if (!(wxyz.norm() > 0.5)) Fail(path + ".rotation_wxyz", "not a rotation quaternion");
    return Sim3d(scale, Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]),
                 Vector(Member(j, "translation", path), path + ".translation"));
  }

 private:
  std::filesystem::path source_;
};

}  // namespace

std::string GeoreferenceToJson(const Georeference& g) {
  const Wgs84& o = g.enu_frame.origin();
  json root = {{"origin", {{"lat", o.latitude_deg}, {"lon", o.longitude_deg}, {"alt", o.altitude_m}}},
               {"enu_from_map", SimJson(g.enu_from_map)}};
  json local = json::array();
  if (g.local) {
    for (const LocalCorrections::Keyframe& k : g.local->keyframes()) {
      local.push_back({{"frame_index", k.frame_index},
                       {"map_position", Vec(k.map_position)},
                       {"enu_from_map", SimJson(k.enu_from_map)}});
    }
  }
  root["local"] = local;
  return root.dump();
}

Georeference GeoreferenceFromJson(const std::string& text, const std::filesystem::path& source) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InputError(SourceLocation{source, 0}, "json", e.what());
  }
  const Reader r(source);
  const json& origin = r.Member(root, "origin", "");
  const Wgs84 o{r.Number(r.Member(origin, "lat", "origin"), "origin.lat"),
                r.Number(r.Member(origin, "lon", "origin"), "origin.lon"),
                r.Number(r.Member(origin, "alt", "origin"), "origin.alt")};
  if (!o.IsValid()) r.Fail("origin", "not a valid WGS84 position");
  const Sim3d global = r.Sim(r.Member(root, "enu_from_map", ""), "enu_from_map");
  std::shared_ptr<const LocalCorrections> local;
  if (root.contains("local")) {
    const json& list = root.at("local");
    if (!list.is_array()) r.Fail("local", "expected an array");
    std::vector<LocalCorrections::Keyframe> keyframes;
    for (size_t i = 0; i < list.size(); ++i) {
      const std::string p = fmt::format("local[{}]", i);
      const json& f = r.Member(list[i], "frame_index", p);
      if (!f.is_number_integer() || f.get<long long>() < 0)
        r.Fail(p + ".frame_index", "expected a non-negative integer");
      keyframes.push_back({static_cast<size_t>(f.get<long long>()),
                           r.Vector(r.Member(list[i], "map_position", p), p + ".map_position"),
                           r.Sim(r.Member(list[i], "enu_from_map", p), p + ".enu_from_map")});
    }
    if (!keyframes.empty()) local = std::make_shared<const LocalCorrections>(std::move(keyframes));
  }
  return Georeference(EnuFrame(o), global, local);
}

}  // namespace semslam
