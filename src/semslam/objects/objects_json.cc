// objects.json (nlohmann_json stays in this file).

#include <nlohmann/json.hpp>

#include "semslam/core/atomic_file.h"
#include "semslam/objects/object_map.h"

namespace semslam {

using nlohmann::json;

namespace {

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

}  // namespace

void WriteObjectsJson(const std::filesystem::path& path, const ObjectMap& map,
                      const ObjectMapOptions& options) {
  json parameters = json::object();
  json counts = json::object();
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassClusterParams& p = options.per_class[static_cast<size_t>(c)];
    const std::string key(ClassKey(c));
    parameters[key] = {{"enabled", p.enabled}, {"eps_m", p.eps_m}, {"min_points", p.min_points}};
    counts[key] = {{"objects", 0},
                   {"clustered_points", map.clustered_points[static_cast<size_t>(c)]},
                   {"noise_points", map.noise_points[static_cast<size_t>(c)]}};
  }
  json objects = json::array();
  for (const SemanticObject& o : map.objects) {
    const std::string key(ClassKey(o.label));
    counts[key]["objects"] = counts[key]["objects"].get<int>() + 1;
    const Eigen::Quaterniond& q = o.pca_box.rotation;
    json object = {{"id", o.id},
                   {"class", std::string(ClassName(o.label))},
                   {"train_id", o.label},
                   {"num_points", o.num_points},
                   {"mean_confidence", o.mean_confidence},
                   {"centroid_map", Vec(o.centroid)},
                   {"aabb_map", {{"min", Vec(o.box_min)}, {"max", Vec(o.box_max)}}},
                   {"pca_box_map",
                    {{"center", Vec(o.pca_box.center)},
                     {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}},
                     {"half_extents", Vec(o.pca_box.half_extents)}}},
                   {"size_m", Vec(o.size_m)}};
    if (o.centroid_enu) object["centroid_enu"] = Vec(*o.centroid_enu);
    if (o.centroid_wgs84) {
      object["centroid_wgs84"] = {{"lat", o.centroid_wgs84->latitude_deg},
                                  {"lon", o.centroid_wgs84->longitude_deg},
                                  {"alt", o.centroid_wgs84->altitude_m}};
    } else {
      object["centroid_wgs84"] = nullptr;
    }
    objects.push_back(std::move(object));
  }
  const json root = {{"format", "semslam-objects"},
                     {"version", 1},
                     {"frame", "map"},
                     {"georeferenced", map.georeferenced},
                     {"metres_per_map_unit", map.metres_per_map_unit},
                     {"scale_source", map.scale_source},
                     {"min_confidence", options.min_confidence},
                     {"parameters", parameters},
                     {"counts", counts},
                     {"num_objects", map.objects.size()},
                     {"objects", objects}};
  WriteFileAtomically(path, root.dump(1) + "\n");
}

}  // namespace semslam
