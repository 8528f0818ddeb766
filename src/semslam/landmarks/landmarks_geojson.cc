// landmarks.geojson (nlohmann_json stays in writer/reader files).

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

}  // namespace semslam
