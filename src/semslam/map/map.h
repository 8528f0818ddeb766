#pragma once
// The map: keyframes and map points, and the one lock that guards them.
//
// Locking: the tracking, local-mapping and loop-closing threads read the map under a shared lock
// (ReadLock) and change it under the exclusive lock (WriteLock); long computations copy what they need,
// release the lock, and write results back under the exclusive lock, checking is_bad() on the way.
// Erased keyframes and points stay allocated until the map is destroyed, so pointers held across locks
// never dangle; they only turn bad.

#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <shared_mutex>
#include <unordered_map>
#include <vector>

#include "semslam/map/by_id.h"
#include "semslam/map/frame.h"
#include "semslam/map/keyframe.h"
#include "semslam/map/map_point.h"

namespace semslam {

class Map {
 public:
  Map() = default;
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  std::shared_lock<std::shared_mutex> ReadLock() const { return std::shared_lock(mutex_); }
  std::unique_lock<std::shared_mutex> WriteLock() const { return std::unique_lock(mutex_); }

  // With the write lock held.
  KeyFrame* AddKeyFrame(const Frame& frame);
  MapPoint* AddMapPoint(const Eigen::Vector3d& position, KeyFrame* reference_keyframe);
  // Removes from the active sets (the caller has marked the object bad).
  void EraseKeyFrame(KeyFrame* keyframe);
  void EraseMapPoint(MapPoint* point);
  // Restores objects with given ids (map loading); ids must be unique.
  KeyFrame* RestoreKeyFrame(std::unique_ptr<KeyFrame> keyframe);
  MapPoint* RestoreMapPoint(std::unique_ptr<MapPoint> point);

  // Empties the active sets (objects stay allocated for pointers still held elsewhere). Write lock.
  void Clear();

  // With a read lock held.
  std::vector<KeyFrame*> KeyFrames() const;        // active, by id
  std::vector<MapPoint*> MapPoints() const;        // active, by id
  KeyFrame* KeyFrameById(std::uint64_t id) const;  // active keyframe with this id, or nullptr
  size_t NumKeyFrames() const { return keyframes_.size(); }
  size_t NumMapPoints() const { return points_.size(); }
  std::uint64_t next_keyframe_id() const { return next_keyframe_id_; }
  std::uint64_t next_point_id() const { return next_point_id_; }

  // Incremented on changes that move many poses at once (loop closure, global BA, map merge), so that
  // tracking knows its motion model is stale.
  int big_change_index() const { return big_change_index_; }
  void NotifyBigChange() { ++big_change_index_; }

  // Points the local mapper created recently (for culling), kept here so culling survives restarts.
  std::vector<MapPoint*> recent_points;

 private:
  mutable std::shared_mutex mutex_;
  std::vector<std::unique_ptr<KeyFrame>> all_keyframes_;
  std::vector<std::unique_ptr<MapPoint>> all_points_;
  std::set<KeyFrame*, ById> keyframes_;
  std::unordered_map<std::uint64_t, KeyFrame*> keyframe_by_id_;
  std::set<MapPoint*, ById> points_;
  std::uint64_t next_keyframe_id_ = 0;
  std::uint64_t next_point_id_ = 0;
  int big_change_index_ = 0;
};

}  // namespace semslam
