#pragma once
// A keyframe: a frame kept in the map, with its features, pose, map point associations, place in the
// covisibility graph and spanning tree, bag-of-words vectors, and links for semantics and GPS.
//
// Thread safety: as for MapPoint, guarded by the owning Map's mutex; "scratch" fields belong to one thread.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <vector>

#include "semslam/features/orb_types.h"
#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/map/by_id.h"
#include "semslam/map/frame.h"
#include "semslam/map/keypoint_labels.h"

namespace semslam {

class MapPoint;

class KeyFrame {
 public:
  // Copies the frame's features, stereo data, bag of words and pose (the frame must have a pose).
  KeyFrame(std::uint64_t id, const Frame& frame);

  std::uint64_t id() const { return id_; }
  std::uint64_t frame_id() const { return frame_id_; }
  double timestamp() const { return timestamp_; }
  // The session (drive) that made this keyframe, and the map it belongs to: a Map may hold several
  // disconnected maps (see map.h); a merge moves a keyframe into another map.
  std::uint32_t session() const { return session_; }
  std::uint32_t map_id() const { return map_id_; }
  // The first keyframe of its map: it fixes the map's frame in optimizations and is never culled.
  bool is_map_origin() const { return map_origin_; }

  // The frame data: features (undistorted pixel coordinates), stereo, grid, bag of words.
  const FrameData& data() const { return *data_; }
  const FeatureSet& features() const { return data_->features; }
  const PinholeCamera& camera() const { return data_->camera; }
  size_t num_features() const { return data_->features.size(); }
  // The same features through another camera: the final bundle adjustment's refined one re-undistorts the
  // keypoints (mapping/map_optimization.h). As many keypoints, in the same order. Write lock.
  void ReplaceData(std::shared_ptr<const FrameData> data);

  const Rigid3d& camera_from_world() const { return camera_from_world_; }
  const Rigid3d& world_from_camera() const { return world_from_camera_; }
  Eigen::Vector3d center() const { return world_from_camera_.translation; }
  void SetPose(const Rigid3d& camera_from_world);
  // How much the map's units around this keyframe have been stretched since it was made: a monocular loop
  // or merge moves a neighbourhood by a Sim(3), and a pose kept relative to this keyframe (a frame's, a
  // culled child's) must stretch with it. 1 until such a correction. A culled keyframe follows its parent
  // (CorrectScale does nothing to it).
  double scale_correction() const;
  void CorrectScale(double scale);

  // Map point associations, one slot per keypoint (nullptr = none).
  const std::vector<MapPoint*>& map_points() const { return map_points_; }
  MapPoint* map_point(int index) const { return map_points_[static_cast<size_t>(index)]; }
  void SetMapPoint(int index, MapPoint* point) { map_points_[static_cast<size_t>(index)] = point; }
  void EraseMapPoint(const MapPoint* point);
  // Good (not bad) points observed by at least `min_observations` cameras.
  int CountTrackedPoints(int min_observations) const;
  std::set<MapPoint*> GoodMapPoints() const;

  // Covisibility graph: keyframes sharing at least 15 points (or the best one) with their weights.
  void UpdateConnections();
  void AddConnection(KeyFrame* other, int weight);
  void EraseConnection(KeyFrame* other);
  std::vector<KeyFrame*> BestCovisibles(size_t n) const;
  std::vector<KeyFrame*> CovisiblesWithWeightAtLeast(int weight) const;
  const std::vector<KeyFrame*>& Covisibles() const { return ordered_connections_; }
  int ConnectionWeight(KeyFrame* other) const;

  // Spanning tree (the strongest covisibility link to an older keyframe; a map's first keyframe is a root) and
  // loop edges.
  KeyFrame* parent() const { return parent_; }
  const std::set<KeyFrame*, ById>& children() const { return children_; }
  // Whether `keyframe` is this one or lies on its path to the root.
  bool HasAncestor(const KeyFrame* keyframe) const;
  // Whether this keyframe is `keyframe` or lies on its path to the root (keyframe->HasAncestor(this)).
  bool IsAncestorOf(const KeyFrame* keyframe) const;
  // Refused (the parent stays) when `parent` descends from this keyframe: that would close a cycle.
  void ChangeParent(KeyFrame* parent);
  void AddLoopEdge(KeyFrame* other);
  const std::set<KeyFrame*, ById>& loop_edges() const { return loop_edges_; }

  // Culling. A keyframe protected by the loop closer is erased only when released.
  bool is_bad() const { return bad_; }
  void SetNotErase() { not_erase_ = true; }
  void SetErase();
  // Disconnects the keyframe from the graph and its points, re-parents its children. A map's origin is
  // never erased.
  void SetBad();
  // Marks the keyframe bad without touching the graph (the whole map is being reset).
  void MarkBadForReset() { bad_ = true; }
  // Pose relative to the parent, kept when the keyframe is erased so trajectories can still be recovered;
  // in the parent's units as they are now (see scale_correction).
  Rigid3d camera_from_parent() const;

  // Median depth of the observed points (for monocular scale and baselines); `q` = 2 gives the median.
  double SceneDepthQuantile(int q = 2) const;
  // Whether a world point projects inside the image with positive depth.
  bool IsInImage(const Eigen::Vector3d& world_point) const;
  // World position of a keypoint with stereo depth, if any.
  std::optional<Eigen::Vector3d> UnprojectStereo(int index) const;

  // Bag of words (computed by the mapping thread when the frame did not have it yet).
  bool has_bow = false;
  BowVector bow;
  FeatureVector feature_vector;

  // Semantics: the class observations of this keyframe's segmentation at its keypoints; empty until the
  // keyframe has been segmented.
  KeypointLabels keypoint_labels;

  // GPS: the fix matched to this keyframe, in the ENU frame (metres), when there is one.
  std::optional<Eigen::Vector3d> gps_enu;
  double gps_sigma_m = 0.0;

  // Scratch (mapping thread).
  std::uint64_t local_ba_keyframe = UINT64_MAX;
  std::uint64_t fixed_ba_keyframe = UINT64_MAX;
  std::uint64_t fuse_target_keyframe = UINT64_MAX;
  // Scratch (tracking thread).
  std::uint64_t tracking_local_frame = UINT64_MAX;
  std::uint64_t relocalization_query_frame = UINT64_MAX;
  // Scratch (loop thread and its global BA).
  std::uint64_t loop_query_keyframe = UINT64_MAX;
  int loop_words = 0;
  float loop_score = 0.0f;
  std::uint64_t global_ba_keyframe = UINT64_MAX;
  Rigid3d global_ba_pose;
  Rigid3d global_ba_pose_before;

 private:
  friend class MapSerializer;
  friend class Map;
  void UpdateBestCovisibles();

  const std::uint64_t id_;
  const std::uint64_t frame_id_;
  const double timestamp_;
  std::uint32_t session_ = 0;
  std::uint32_t map_id_ = 0;
  bool map_origin_ = false;
  std::shared_ptr<const FrameData> data_;
  Rigid3d camera_from_world_;
  Rigid3d world_from_camera_;
  std::vector<MapPoint*> map_points_;

  std::map<KeyFrame*, int, ById> connection_weights_;
  std::vector<KeyFrame*> ordered_connections_;
  std::vector<int> ordered_weights_;
  bool first_connection_ = true;
  KeyFrame* parent_ = nullptr;
  std::set<KeyFrame*, ById> children_;
  std::set<KeyFrame*, ById> loop_edges_;

  bool bad_ = false;
  bool not_erase_ = false;
  bool to_be_erased_ = false;
  Rigid3d camera_from_parent_;
  // The parent's scale_correction() when camera_from_parent_ was taken.
  double parent_scale_when_erased_ = 1.0;
  double scale_correction_ = 1.0;
};

// The good keyframe standing for `kf`: itself, or the nearest good ancestor of a culled one (culling hands a
// keyframe's dependants to its parent through the relative pose it keeps). `x_from_kf`, a pose relative to kf
// in kf's units when its scale_correction() was `units`, comes back as x_from_ancestor in the ancestor's
// units now. {nullptr, {}} when no good ancestor is left (its map was given up).
std::pair<KeyFrame*, Rigid3d> GoodAncestor(KeyFrame* kf, Rigid3d x_from_kf, double units);

}  // namespace semslam
