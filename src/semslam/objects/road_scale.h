#pragma once
// A monocular map's scale from the road beneath the camera. The camera rides at a known height above the road
// (its mount), and the map's road points give that height in map units: their ratio is the map's metres per
// unit (the ground-plane constraint of monocular driving odometry, e.g. Song & Chandraker, CVPR 2014). It
// lets a map without GPS give objects their sizes and clustering radii in metres.
//
// Per keyframe, a plane is fitted (RANSAC, then least squares) to the road points nearest the camera ahead of
// and below it; its distance from the camera centre is the camera's height there. The map's height is the
// median over the keyframes that fit one: a drifting scale gives its median along the drive, and keyframes
// whose fit mislabelled points spoilt fall outside the middle.

#include <optional>
#include <vector>

#include "semslam/geometry/rigid3.h"
#include "semslam/objects/object_map.h"

namespace semslam {

struct RoadScaleOptions {
  // The camera's height above the road, metres: KITTI's cameras (Geiger et al. 2013: 1.65 m) and the
  // synthetic city's.
  double camera_height_m = 1.65;
  int nearest_points = 60;  // road points nearest the camera one keyframe fits its plane to
  int min_inliers = 20;     // of those, within the RANSAC's distance of the plane
  // That distance, a share of the camera's height (the nearest points' median depth below it).
  double inlier_share = 0.05;
  double max_tilt_deg = 15.0;   // between the plane's normal and the camera's down axis
  int min_keyframes = 5;        // keyframes with a plane, for a scale
  int ransac_iterations = 100;  // plane hypotheses per keyframe

  void Check() const;  // throws InvalidArgument
};

struct RoadScale {
  double metres_per_map_unit = 1.0;
  double camera_height_map = 0.0;  // median over the keyframes, map units
  // Half the range of the middle half of the keyframes' heights, over their median: how much the map's scale
  // varies along the drive (and the fits' noise).
  double spread = 0.0;
  int keyframes = 0;  // that fitted a plane
};

// `world_from_camera` per keyframe (camera x right, y down, z forward); `points` the labelled map points
// (only road points are used). Empty when fewer than options.min_keyframes keyframes fit a plane.
std::optional<RoadScale> EstimateRoadScale(const std::vector<Rigid3d>& world_from_camera,
                                           const std::vector<LabeledPoint>& points,
                                           const RoadScaleOptions& options = {});

}  // namespace semslam
