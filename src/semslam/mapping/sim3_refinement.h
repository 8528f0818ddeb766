#pragma once
// The Sim(3) between two keyframes refined by the reprojection of the map points they match: the loop
// closer's last step after the RANSAC, for a loop and for a merge of two maps.

#include <optional>
#include <vector>

#include "semslam/geometry/sim3.h"
#include "semslam/map/keyframe.h"
#include "semslam/map/map_point.h"

namespace semslam {

// Refines kf1_from_kf2 by the reprojection of matched points in both keyframes; outlier matches are
// cleared from `matches12`. Returns the inlier count. Read lock.
int RefineSim3(const KeyFrame& kf1, const KeyFrame& kf2, std::vector<MapPoint*>& matches12,
               Sim3d* kf1_from_kf2, double chi2_threshold, bool fix_scale);

// MedianDepthRatio (geometry/sim3_solver.h) of the matched points of two keyframes under kf1_from_kf2:
// about 1 when it aligns the two structures. nullopt without a usable match.
std::optional<double> StructureDepthRatio(const KeyFrame& kf1, const KeyFrame& kf2,
                                          const std::vector<MapPoint*>& matches12, const Sim3d& kf1_from_kf2);

struct MonocularSim3Refinement {
  int inliers = 0;
  bool scale_held = false;        // the free refinement disagreed with the structures
  double free_scale = 0.0;        // the free refinement's scale
  double free_depth_ratio = 0.0;  // and its StructureDepthRatio (0 without a usable match)
};

// RefineSim3 with a free scale, checked against the two keyframes' own points: where the two cameras stand
// close together, reprojection barely holds the scale, and a refinement that leaves the matched points beyond
// `max_depth_ratio` of their own depth (StructureDepthRatio) is run again, on all the matches, with its scale
// multiplied by that ratio and held: the scale the two structures give. Read lock.
MonocularSim3Refinement RefineSim3KeepingStructureScale(const KeyFrame& kf1, const KeyFrame& kf2,
                                                        std::vector<MapPoint*>& matches12,
                                                        Sim3d* kf1_from_kf2, double chi2_threshold,
                                                        double max_depth_ratio);

}  // namespace semslam
