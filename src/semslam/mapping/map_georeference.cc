#include "semslam/mapping/map_georeference.h"

namespace semslam {

namespace {

// camera_from_world of a similarity world_from_camera, without its scale: the rigid pose of the same camera.
Rigid3d RigidCameraFromWorld(const Sim3d& world_from_camera) {
  const Sim3d camera_from_world = world_from_camera.Inverse();
  return Rigid3d(camera_from_world.rotation, camera_from_world.translation / camera_from_world.scale);
}

}  // namespace

int MoveMapIntoWorld(Map& map, std::uint32_t map_id,
                     const std::unordered_map<std::uint64_t, Sim3d>& world_from_keyframe,
                     const Sim3d& world_from_map) {
  // world_from_new * old_from_world (the change each keyframe makes), for every keyframe of the map: its own,
  // or its nearest ancestor's.
  std::unordered_map<const KeyFrame*, Sim3d> change;
  const std::vector<KeyFrame*> keyframes = map.KeyFramesOfMap(map_id);
  for (KeyFrame* kf : keyframes) {
    const auto it = world_from_keyframe.find(kf->id());
    if (it != world_from_keyframe.end()) change[kf] = it->second * Sim3d(kf->camera_from_world());
  }
  const auto change_of = [&](const KeyFrame* kf) -> const Sim3d* {
    for (const KeyFrame* k = kf; k != nullptr; k = k->parent()) {
      const auto it = change.find(k);
      if (it != change.end()) return &it->second;
    }
    return &world_from_map;
  };
  int placed = 0;
  for (KeyFrame* kf : keyframes) {
    const Sim3d* c = change_of(kf);
    const Sim3d world_from_camera = *c * Sim3d(kf->world_from_camera());
    kf->SetPose(RigidCameraFromWorld(world_from_camera));
    kf->CorrectScale(world_from_camera.scale);
    placed += world_from_keyframe.count(kf->id()) > 0 ? 1 : 0;
  }
  // After the keyframes: a point's normal and depth range are measured from them.
  for (MapPoint* p : map.MapPointsOfMap(map_id)) {
    if (p->is_bad()) continue;
    p->SetPosition(*change_of(p->reference_keyframe()) * p->position());
    p->UpdateNormalAndDepth();
  }
  map.NotifyBigChange();
  return placed;
}

}  // namespace semslam
