#pragma once
// The map: keyframes and map points, and the one lock that guards them.
//
// Locking: the tracking, local-mapping and loop-closing threads read the map under a shared lock
// (ReadLock) and change it under the exclusive lock (WriteLock); long computations copy what they need,
// release the lock, and write results back under the exclusive lock, checking is_bad() on the way.
// Erased keyframes and points stay allocated until the map is destroyed, so pointers held across locks
// never dangle; they only turn bad.
//
// Several maps in one (an atlas, after ORB-SLAM3, Campos et al. 2021): when tracking is lost for good, a new
// map starts, with a frame of reference of its own, and the old ones are kept; when a place of an older map
// is recognized, the two are merged into one. Every keyframe carries the id of its map (points follow their
// reference keyframe); the active map is the one tracking and mapping extend. Every keyframe also carries
// its session: the drive (run) that made it, so that a map reused by later runs knows whose frames are
// whose.

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <shared_mutex>
#include <string>
#include <unordered_map>
#include <vector>

#include "semslam/map/by_id.h"
#include "semslam/map/frame.h"
#include "semslam/map/keyframe.h"
#include "semslam/map/map_point.h"

namespace semslam {

// A drive that added keyframes to the map (one run of semslam).
struct MapSession {
  std::uint32_t id = 0;
  std::string name;    // the sequence's name
  std::string source;  // where its frames came from (the sequence path)
};

// Where tracking took up again after a loss, as the motion model saw it: the first keyframe of the map
// started after the loss (`after`), relative to the last keyframe tracked in the lost map (`before`), from
// the motion before the loss carried over the time without a pose. Nothing in the images ties the two
// maps there; once they are merged (at a place seen in both), this link keeps the trajectory from folding at
// the gap (loop closing weighs it as the rough prediction it is), and bundle adjustments hold its ends where
// the loop correction put them (mapping/gap_link_priors.h).
struct GapLink {
  KeyFrame* before = nullptr;
  KeyFrame* after = nullptr;
  Rigid3d after_from_before;  // in the lost map's units
  double before_scale = 1.0;  // before->scale_correction() then (the link stretches with the map there)
};

// A gap link between the good keyframes standing for its two ends (each end itself, or the nearest good
// ancestor of a culled one), as before_from_after between them; nullopt when an end has none (its map was
// given up).
struct GapEdge {
  KeyFrame* before = nullptr;
  KeyFrame* after = nullptr;
  Rigid3d before_from_after;
};
std::optional<GapEdge> ResolveGapLink(const GapLink& link);

class Map {
 public:
  Map() = default;
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  std::shared_lock<std::shared_mutex> ReadLock() const { return std::shared_lock(mutex_); }
  std::unique_lock<std::shared_mutex> WriteLock() const { return std::unique_lock(mutex_); }

  // With the write lock held.
  // A keyframe of the active map and the current session; the first keyframe of a map is its origin.
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

  // Sessions. A new Map has session 0 with no name; BeginSession starts another one (a run that reuses a
  // loaded map) and returns its id. Write lock.
  std::uint32_t BeginSession(std::string name, std::string source);
  void NameCurrentSession(std::string name, std::string source);
  void RestoreSessions(std::vector<MapSession> sessions);  // map loading: the stored table
  const std::vector<MapSession>& sessions() const { return sessions_; }
  std::uint32_t current_session() const { return current_session_; }

  // Maps. StartNewMap makes a new, empty map active (the next keyframe is its origin) and returns its id;
  // ActivateMap makes an existing one active. MergeMapInto moves every keyframe of map `from` (poses and
  // points already expressed in the frame of `into`) into map `into`, which becomes active if `from` was.
  // DiscardMap erases a whole map (a young one given up). Write lock.
  std::uint32_t StartNewMap();
  void ActivateMap(std::uint32_t map_id);
  void MergeMapInto(std::uint32_t from, std::uint32_t into);
  void DiscardMap(std::uint32_t map_id);
  std::uint32_t active_map_id() const { return active_map_id_; }
  std::uint32_t next_map_id() const { return next_map_id_; }
  void RestoreMapIds(std::uint32_t active, std::uint32_t next);  // map loading

  // With a read lock held: the maps that hold keyframes (ascending ids), and their contents.
  std::vector<std::uint32_t> MapIds() const;
  std::vector<KeyFrame*> KeyFramesOfMap(std::uint32_t map_id) const;  // by id
  std::vector<MapPoint*> MapPointsOfMap(std::uint32_t map_id) const;  // by id
  size_t NumKeyFramesOfMap(std::uint32_t map_id) const;
  // The map with the most keyframes (the lowest id of a tie); the active one when no map has any.
  std::uint32_t MapWithMostKeyFrames() const;

  // With a read lock held.
  std::vector<KeyFrame*> KeyFrames() const;        // active, by id
  std::vector<MapPoint*> MapPoints() const;        // active, by id
  KeyFrame* KeyFrameById(std::uint64_t id) const;  // active keyframe with this id, or nullptr
  size_t NumKeyFrames() const { return keyframes_.size(); }
  size_t NumMapPoints() const { return points_.size(); }
  std::uint64_t next_keyframe_id() const { return next_keyframe_id_; }
  std::uint64_t next_point_id() const { return next_point_id_; }

  // Gap links (see GapLink). Add: write lock; read: read lock.
  void AddGapLink(const GapLink& link) { gap_links_.push_back(link); }
  const std::vector<GapLink>& gap_links() const { return gap_links_; }

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
  std::vector<MapSession> sessions_ = {MapSession{}};
  std::uint32_t current_session_ = 0;
  std::uint32_t active_map_id_ = 0;
  std::uint32_t next_map_id_ = 1;
  std::vector<GapLink> gap_links_;
};

}  // namespace semslam
