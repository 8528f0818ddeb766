#pragma once
// A camera frame being tracked: its features (in undistorted pixel coordinates), stereo measurements,
// the map points matched to its keypoints, and its pose once tracked.

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "semslam/features/feature_grid.h"
#include "semslam/features/orb_types.h"
#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/place/bow_vector.h"

namespace semslam {

class MapPoint;
class KeyFrame;

// What a frame measured; immutable once built and shared by the frame and its keyframe.
struct FrameData {
  PinholeCamera camera;  // ideal pinhole: keypoints are undistorted
  std::optional<StereoRig> stereo;
  FeatureSet features;
  std::vector<float> right_u;  // stereo: u in the right image per keypoint, < 0 when unmatched
  std::vector<float> depth;    // stereo: depth per keypoint, < 0 when unknown
  FeatureGrid grid;
  // Bounds of the undistorted image (equal to the image for an undistorted camera).
  float min_x = 0, max_x = 0, min_y = 0, max_y = 0;

  bool HasDepth(int i) const { return !depth.empty() && depth[static_cast<size_t>(i)] > 0; }
  bool InBounds(float x, float y) const { return x >= min_x && x < max_x && y >= min_y && y < max_y; }
};

// Builds the frame data from raw features: undistorts keypoints, computes bounds, builds the grid.
// `right_u` and `depth` may be empty (monocular).
std::shared_ptr<FrameData> MakeFrameData(const PinholeCamera& camera, const std::optional<StereoRig>& stereo,
                                         FeatureSet features, std::vector<float> right_u,
                                         std::vector<float> depth);

class Frame {
 public:
  Frame(std::uint64_t id, double timestamp, std::shared_ptr<const FrameData> data);

  std::uint64_t id() const { return id_; }
  double timestamp() const { return timestamp_; }
  const FrameData& data() const { return *data_; }
  const std::shared_ptr<const FrameData>& shared_data() const { return data_; }
  const FeatureSet& features() const { return data_->features; }
  size_t num_features() const { return data_->features.size(); }

  bool has_pose() const { return camera_from_world_.has_value(); }
  const Rigid3d& camera_from_world() const { return *camera_from_world_; }
  const Rigid3d& world_from_camera() const { return world_from_camera_; }
  Eigen::Vector3d center() const { return world_from_camera_.translation; }
  void SetPose(const Rigid3d& camera_from_world);

  // Matched map points, one slot per keypoint, and whether pose optimization rejected the match.
  std::vector<MapPoint*> map_points;
  std::vector<bool> outliers;
  int CountMatches() const;
  // Drops every match and the reference keyframe (a frame that failed to track keeps nothing of the map it
  // was tried in).
  void ClearMatches();

  // Bag of words, computed on demand (relocalization) or when the frame becomes a keyframe.
  bool has_bow = false;
  BowVector bow;
  FeatureVector feature_vector;

  KeyFrame* reference_keyframe = nullptr;

 private:
  std::uint64_t id_;
  double timestamp_;
  std::shared_ptr<const FrameData> data_;
  std::optional<Rigid3d> camera_from_world_;
  Rigid3d world_from_camera_;
};

}  // namespace semslam
