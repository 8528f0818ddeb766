#include "semslam/map/map.h"

#include <algorithm>

namespace semslam {

KeyFrame* Map::AddKeyFrame(const Frame& frame) {
  all_keyframes_.push_back(std::make_unique<KeyFrame>(next_keyframe_id_++, frame));
  KeyFrame* keyframe = all_keyframes_.back().get();
  keyframes_.insert(keyframe);
  keyframe_by_id_[keyframe->id()] = keyframe;
  return keyframe;
}

MapPoint* Map::AddMapPoint(const Eigen::Vector3d& position, KeyFrame* reference_keyframe) {
  all_points_.push_back(std::make_unique<MapPoint>(next_point_id_++, position, reference_keyframe));
  MapPoint* point = all_points_.back().get();
  points_.insert(point);
  return point;
}

void Map::EraseKeyFrame(KeyFrame* keyframe) {
  keyframes_.erase(keyframe);
  keyframe_by_id_.erase(keyframe->id());
}
void Map::EraseMapPoint(MapPoint* point) { points_.erase(point); }

KeyFrame* Map::RestoreKeyFrame(std::unique_ptr<KeyFrame> keyframe) {
  next_keyframe_id_ = std::max(next_keyframe_id_, keyframe->id() + 1);
  all_keyframes_.push_back(std::move(keyframe));
  KeyFrame* k = all_keyframes_.back().get();
  keyframes_.insert(k);
  keyframe_by_id_[k->id()] = k;
  return k;
}

MapPoint* Map::RestoreMapPoint(std::unique_ptr<MapPoint> point) {
  next_point_id_ = std::max(next_point_id_, point->id() + 1);
  all_points_.push_back(std::move(point));
  MapPoint* p = all_points_.back().get();
  points_.insert(p);
  return p;
}

void Map::Clear() {
  for (KeyFrame* kf : keyframes_) kf->MarkBadForReset();
  for (MapPoint* p : points_) p->MarkBadForReset();
  keyframes_.clear();
  keyframe_by_id_.clear();
  points_.clear();
  recent_points.clear();
  ++big_change_index_;
}

std::vector<KeyFrame*> Map::KeyFrames() const { return {keyframes_.begin(), keyframes_.end()}; }
std::vector<MapPoint*> Map::MapPoints() const { return {points_.begin(), points_.end()}; }

KeyFrame* Map::KeyFrameById(std::uint64_t id) const {
  const auto it = keyframe_by_id_.find(id);
  return it == keyframe_by_id_.end() ? nullptr : it->second;
}

}  // namespace semslam
