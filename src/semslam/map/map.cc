#include "semslam/map/map.h"

#include <algorithm>
#include <map>
#include <set>

#include "semslam/core/error.h"

namespace semslam {

KeyFrame* Map::AddKeyFrame(const Frame& frame) {
  all_keyframes_.push_back(std::make_unique<KeyFrame>(next_keyframe_id_++, frame));
  KeyFrame* keyframe = all_keyframes_.back().get();
  keyframe->session_ = current_session_;
  keyframe->map_id_ = active_map_id_;
  keyframe->map_origin_ = NumKeyFramesOfMap(active_map_id_) == 0;
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
  gap_links_.clear();
  ++big_change_index_;
}

std::uint32_t Map::BeginSession(std::string name, std::string source) {
  const auto id = static_cast<std::uint32_t>(sessions_.size());
  sessions_.push_back({id, std::move(name), std::move(source)});
  current_session_ = id;
  return id;
}

void Map::NameCurrentSession(std::string name, std::string source) {
  sessions_[current_session_].name = std::move(name);
  sessions_[current_session_].source = std::move(source);
}

void Map::RestoreSessions(std::vector<MapSession> sessions) {
  Require(!sessions.empty(), "a map has at least one session");
  for (size_t i = 0; i < sessions.size(); ++i)
    Require(sessions[i].id == i, "session ids must be 0, 1, 2, ... in order");
  sessions_ = std::move(sessions);
  current_session_ = static_cast<std::uint32_t>(sessions_.size() - 1);
}

std::optional<GapEdge> ResolveGapLink(const GapLink& link) {
  const auto [before, before_from_stand_in] =
      GoodAncestor(link.before, Rigid3d(), link.before->scale_correction());
  const auto [after, after_from_stand_in] =
      GoodAncestor(link.after, Rigid3d(), link.after->scale_correction());
  if (before == nullptr || after == nullptr || before == after) return std::nullopt;
  const Rigid3d after_from_before =
      Stretched(link.after_from_before, link.before->scale_correction() / link.before_scale);
  return GapEdge{before, after,
                 before_from_stand_in.Inverse() * after_from_before.Inverse() * after_from_stand_in};
}

std::uint32_t Map::StartNewMap() {
  active_map_id_ = next_map_id_++;
  ++big_change_index_;
  return active_map_id_;
}

void Map::ActivateMap(std::uint32_t map_id) {
  Require(map_id < next_map_id_, "ActivateMap: no such map");
  if (map_id != active_map_id_) ++big_change_index_;
  active_map_id_ = map_id;
}

void Map::MergeMapInto(std::uint32_t from, std::uint32_t into) {
  Require(from != into, "MergeMapInto: a map cannot merge into itself");
  for (KeyFrame* kf : keyframes_) {
    if (kf->map_id_ != from) continue;
    kf->map_id_ = into;
    kf->map_origin_ = false;
  }
  if (active_map_id_ == from) active_map_id_ = into;
  ++big_change_index_;
}

void Map::DiscardMap(std::uint32_t map_id) {
  for (MapPoint* p : MapPointsOfMap(map_id)) {
    p->MarkBadForReset();
    EraseMapPoint(p);
  }
  for (KeyFrame* kf : KeyFramesOfMap(map_id)) {
    kf->MarkBadForReset();
    EraseKeyFrame(kf);
  }
  std::erase_if(recent_points, [](const MapPoint* p) { return p->is_bad(); });
  ++big_change_index_;
}

void Map::RestoreMapIds(std::uint32_t active, std::uint32_t next) {
  Require(active < next, "the active map id must be below the next map id");
  for (const KeyFrame* kf : keyframes_) Require(kf->map_id_ < next, "a keyframe's map id is out of range");
  active_map_id_ = active;
  next_map_id_ = next;
}

std::vector<std::uint32_t> Map::MapIds() const {
  std::set<std::uint32_t> ids;
  for (const KeyFrame* kf : keyframes_) ids.insert(kf->map_id());
  return {ids.begin(), ids.end()};
}

std::vector<KeyFrame*> Map::KeyFramesOfMap(std::uint32_t map_id) const {
  std::vector<KeyFrame*> out;
  for (KeyFrame* kf : keyframes_) {
    if (kf->map_id() == map_id) out.push_back(kf);
  }
  return out;
}

std::vector<MapPoint*> Map::MapPointsOfMap(std::uint32_t map_id) const {
  std::vector<MapPoint*> out;
  for (MapPoint* p : points_) {
    if (p->map_id() == map_id) out.push_back(p);
  }
  return out;
}

size_t Map::NumKeyFramesOfMap(std::uint32_t map_id) const {
  return static_cast<size_t>(std::count_if(keyframes_.begin(), keyframes_.end(),
                                           [map_id](const KeyFrame* kf) { return kf->map_id() == map_id; }));
}

std::uint32_t Map::MapWithMostKeyFrames() const {
  std::map<std::uint32_t, size_t> counts;
  for (const KeyFrame* kf : keyframes_) ++counts[kf->map_id()];
  std::uint32_t most = active_map_id_;
  size_t most_count = 0;
  for (const auto& [map_id, count] : counts) {
    if (count > most_count) {
      most = map_id;
      most_count = count;
    }
  }
  return most;
}

std::vector<KeyFrame*> Map::KeyFrames() const { return {keyframes_.begin(), keyframes_.end()}; }
std::vector<MapPoint*> Map::MapPoints() const { return {points_.begin(), points_.end()}; }

KeyFrame* Map::KeyFrameById(std::uint64_t id) const {
  const auto it = keyframe_by_id_.find(id);
  return it == keyframe_by_id_.end() ? nullptr : it->second;
}

}  // namespace semslam
