#pragma once
// A 3D point of the map: position, the keyframes that observe it, a representative descriptor, its
// scale-invariance range, and (for semantics) a distribution over the 19 classes.
//
// Thread safety: every non-atomic member is guarded by the owning Map's mutex (see map.h): read under a
// shared lock, modified under the exclusive lock. Fields marked "scratch" belong to one thread only.

#include <atomic>
#include <cstdint>
#include <map>
#include <vector>

#include "semslam/features/orb_types.h"
#include "semslam/geometry/eigen_types.h"
#include "semslam/map/by_id.h"
#include "semslam/semantics/label_fusion.h"

namespace semslam {

class KeyFrame;

class MapPoint {
 public:
  MapPoint(std::uint64_t id, const Eigen::Vector3d& position, KeyFrame* reference_keyframe);

  std::uint64_t id() const { return id_; }
  std::uint64_t first_keyframe_id() const { return first_keyframe_id_; }

  const Eigen::Vector3d& position() const { return position_; }
  void SetPosition(const Eigen::Vector3d& position) { position_ = position; }
  // Mean viewing direction (unit, from the observing cameras to the point).
  const Eigen::Vector3d& normal() const { return normal_; }
  const Descriptor& descriptor() const { return descriptor_; }
  KeyFrame* reference_keyframe() const { return reference_keyframe_; }
  // The map the point belongs to: its reference keyframe's.
  std::uint32_t map_id() const;

  // Observations: keyframe -> keypoint index in that keyframe.
  const std::map<KeyFrame*, int, ById>& observations() const { return observations_; }
  // Number of observing cameras (a stereo observation counts twice, as in the literature).
  int num_observations() const { return num_observations_; }
  // When the keyframe is already segmented, its class observation at the keypoint is fused into the point's
  // labels (unless `fuse_labels` is false: restoring a stored map whose labels already hold it).
  void AddObservation(KeyFrame* keyframe, int keypoint_index, bool fuse_labels = true);
  // Removes the observation; the point turns bad when fewer than 3 camera observations remain.
  void EraseObservation(KeyFrame* keyframe);
  int IndexIn(const KeyFrame* keyframe) const;
  bool IsObservedBy(const KeyFrame* keyframe) const { return IndexIn(keyframe) >= 0; }

  bool is_bad() const { return bad_; }
  // Marks the point bad and removes it from every observing keyframe.
  void SetBad();
  // Marks the point bad without touching observations (the whole map is being reset).
  void MarkBadForReset() { bad_ = true; }
  // Moves every observation to `other` (duplicate fusion) and marks this point bad.
  void ReplaceWith(MapPoint* other);
  // The live point this one was merged into (follows chains), or this point itself.
  MapPoint* Resolve();

  // Recomputes the descriptor (the observation descriptor with the least median distance to the others).
  void UpdateDescriptor();
  // Recomputes the normal and the distance range [min_distance, max_distance] of scale invariance.
  void UpdateNormalAndDepth();
  float min_distance() const { return 0.8f * min_distance_; }
  float max_distance() const { return 1.2f * max_distance_; }
  int PredictLevel(float distance, const PyramidGeometry& pyramid) const;

  // Tracking statistics: how often the point was predicted visible and how often it was matched.
  void IncreaseVisible(int n = 1) { visible_.fetch_add(n, std::memory_order_relaxed); }
  void IncreaseFound(int n = 1) { found_.fetch_add(n, std::memory_order_relaxed); }
  float FoundRatio() const;
  int visible() const { return visible_.load(std::memory_order_relaxed); }
  int found() const { return found_.load(std::memory_order_relaxed); }

  // Semantics: the fused class distribution (semantics/label_fusion.h).
  LabelDistribution& labels() { return labels_; }
  const LabelDistribution& labels() const { return labels_; }
  // Whether the point most probably lies on something that moves (person, rider, vehicle).
  bool IsDynamic() const { return labels_.HasObservations() && labels_.DynamicProbability() > 0.5f; }

  // Scratch (tracking thread): frame id for which the point is already in the local map / was matched.
  std::uint64_t tracking_local_map_frame = UINT64_MAX;
  std::uint64_t tracking_last_seen_frame = UINT64_MAX;
  // Scratch (tracking thread): projection of the point into the current frame.
  bool track_in_view = false;
  float track_u = 0, track_v = 0, track_right_u = -1, track_view_cos = 0;
  int track_level = 0;
  // Scratch (mapping thread): keyframe ids for local BA and neighbour fusion.
  std::uint64_t local_ba_keyframe = UINT64_MAX;
  std::uint64_t fuse_candidate_keyframe = UINT64_MAX;
  // Scratch (loop thread): loop bookkeeping and positions from global BA.
  std::uint64_t loop_point_keyframe = UINT64_MAX;
  std::uint64_t corrected_by_keyframe = UINT64_MAX;
  std::uint64_t corrected_reference = UINT64_MAX;
  std::uint64_t global_ba_keyframe = UINT64_MAX;
  Eigen::Vector3d global_ba_position = Eigen::Vector3d::Zero();

 private:
  friend class MapSerializer;

  const std::uint64_t id_;
  std::uint64_t first_keyframe_id_;
  Eigen::Vector3d position_;
  Eigen::Vector3d normal_ = Eigen::Vector3d::Zero();
  Descriptor descriptor_{};
  float min_distance_ = 0.0f;
  float max_distance_ = 0.0f;
  KeyFrame* reference_keyframe_;
  std::map<KeyFrame*, int, ById> observations_;
  int num_observations_ = 0;
  std::atomic<int> visible_{1};
  std::atomic<int> found_{1};
  bool bad_ = false;
  MapPoint* replaced_by_ = nullptr;
  LabelDistribution labels_;
};

}  // namespace semslam
