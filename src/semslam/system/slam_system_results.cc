// What a run has produced so far, read from the map as it stands: frame and keyframe trajectories, the
// keyframes' edges for GPS fusion, and the run's statistics.

#include <algorithm>
#include <unordered_map>

#include "semslam/system/slam_system.h"

namespace semslam {

Trajectory SlamSystem::FrameTrajectory() const {
  Trajectory trajectory;
  for (const FramePose& pose : FramePoses()) trajectory.push_back({pose.timestamp, pose.world_from_camera});
  return trajectory;
}

std::vector<FramePose> SlamSystem::AllFramePoses() const {
  auto lock = map_->ReadLock();
  std::vector<FramePose> poses;
  for (const FrameRecord& record : tracker_->records()) {
    const KeyFrame* reference = CurrentReference(record);
    const std::optional<Rigid3d> camera_from_world = CurrentCameraFromWorld(record);
    if (reference == nullptr || !camera_from_world) continue;
    FramePose pose{static_cast<size_t>(record.frame_id), -1, record.timestamp, camera_from_world->Inverse()};
    pose.map_id = reference->map_id();
    pose.predicted = record.source == PoseProvenance::kPredicted;
    poses.push_back(pose);
  }
  return poses;
}

std::map<std::uint32_t, size_t> SlamSystem::TrackedFramesPerMap() const {
  std::map<std::uint32_t, size_t> frames;
  for (const FramePose& pose : AllFramePoses()) {
    if (!pose.predicted) ++frames[pose.map_id];
  }
  return frames;
}

std::uint32_t SlamSystem::MainMapId() const {
  std::uint32_t main = 0;
  size_t most = 0;
  for (const auto& [map_id, count] : TrackedFramesPerMap()) {
    if (count > most) {
      most = count;
      main = map_id;
    }
  }
  if (most > 0) return main;
  auto lock = map_->ReadLock();
  return map_->active_map_id();
}

std::vector<FramePose> SlamSystem::FramePoses() const { return FramePoses(MainMapId()); }

std::vector<FramePose> SlamSystem::FramePoses(std::uint32_t map_id) const {
  std::vector<FramePose> poses = AllFramePoses();
  std::erase_if(poses, [map_id](const FramePose& p) { return p.predicted || p.map_id != map_id; });
  return poses;
}

std::vector<FramePose> SlamSystem::KeyFramePoses() const { return KeyFramePoses(MainMapId(), false); }

std::vector<FramePose> SlamSystem::KeyFramePoses(std::uint32_t map_id, bool all_sessions) const {
  auto lock = map_->ReadLock();
  std::vector<FramePose> poses;
  for (const KeyFrame* kf : map_->KeyFramesOfMap(map_id)) {
    if (kf->is_bad() || (!all_sessions && kf->session() != map_->current_session())) continue;
    FramePose pose{static_cast<size_t>(kf->frame_id()), static_cast<long long>(kf->id()), kf->timestamp(),
                   kf->world_from_camera()};
    pose.map_id = map_id;
    poses.push_back(pose);
  }
  // Sessions in order, then frames: frame indices restart with each session.
  std::stable_sort(poses.begin(), poses.end(), [this](const FramePose& a, const FramePose& b) {
    const std::uint32_t sa = map_->KeyFrameById(static_cast<std::uint64_t>(a.keyframe_id))->session();
    const std::uint32_t sb = map_->KeyFrameById(static_cast<std::uint64_t>(b.keyframe_id))->session();
    return sa != sb ? sa < sb : a.frame_index < b.frame_index;
  });
  return poses;
}

std::vector<FusionEdge> SlamSystem::KeyFrameEdges(int min_covisibility_weight) const {
  return KeyFrameEdges(KeyFramePoses(), min_covisibility_weight);
}

std::vector<FusionEdge> SlamSystem::KeyFrameEdges(const std::vector<FramePose>& keyframes,
                                                  int min_covisibility_weight) const {
  auto lock = map_->ReadLock();
  std::unordered_map<std::uint64_t, int> index;
  for (size_t i = 0; i < keyframes.size(); ++i)
    index[static_cast<std::uint64_t>(keyframes[i].keyframe_id)] = static_cast<int>(i);
  std::vector<FusionEdge> edges;
  auto add = [&](const KeyFrame* a, const KeyFrame* b, FusionEdgeKind kind) {
    const auto ia = index.find(a->id()), ib = index.find(b->id());
    if (ia == index.end() || ib == index.end() || ia->second >= ib->second) return;
    edges.push_back(
        {ia->second, ib->second, Sim3d(a->camera_from_world() * b->world_from_camera()), kind, 1.0});
  };
  for (const KeyFrame* kf : map_->KeyFrames()) {
    if (kf->is_bad()) continue;
    for (const KeyFrame* other : kf->loop_edges()) add(kf, other, FusionEdgeKind::kLoop);
    for (KeyFrame* other : kf->CovisiblesWithWeightAtLeast(min_covisibility_weight))
      add(kf, other, FusionEdgeKind::kCovisibility);
  }
  return edges;
}

Trajectory SlamSystem::KeyFrameTrajectory() const {
  Trajectory trajectory;
  for (const FramePose& pose : KeyFramePoses())
    trajectory.push_back({pose.timestamp, pose.world_from_camera});
  return trajectory;
}

SlamStatistics SlamSystem::Statistics() const {
  SlamStatistics s;
  s.frames = frames_;
  for (const FramePose& pose : AllFramePoses()) {
    ++(pose.predicted ? s.predicted : s.with_pose);
  }
  s.tracked = tracked_;
  s.relocalizations = static_cast<size_t>(tracker_->num_relocalizations());
  s.maps_started = static_cast<size_t>(tracker_->num_new_maps());
  s.merges = loop_closer_->merges().size();
  s.loops = loop_closer_->loops().size();
  s.resets = resets_;
  s.segmented_keyframes = segmented_keyframes_.load();
  s.segmented_frames = segmented_frames_.load();
  auto lock = map_->ReadLock();
  s.keyframes = map_->NumKeyFrames();
  s.maps = map_->MapIds().size();
  for (const FrameRecord& record : tracker_->records()) {
    if (record.source == PoseProvenance::kInterpolated) ++s.interpolated;
  }
  s.keyframes_created = map_->next_keyframe_id();
  s.points_created = map_->next_point_id();
  for (const MapPoint* p : map_->MapPoints()) s.map_points += p->is_bad() ? 0 : 1;
  return s;
}

std::vector<LoopEvent> SlamSystem::Loops() const { return loop_closer_->loops(); }
std::vector<LoopEvent> SlamSystem::Merges() const { return loop_closer_->merges(); }

}  // namespace semslam
