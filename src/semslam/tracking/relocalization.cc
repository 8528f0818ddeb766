#include "semslam/tracking/relocalization.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "semslam/geometry/pnp.h"
#include "semslam/map/map_matcher.h"
#include "semslam/map/place_candidates.h"
#include "semslam/place/keyframe_database.h"

namespace semslam {

bool RelocalizeFrame(Frame& frame, const KeyFrameDatabase& database, const Map& map,
                     const std::function<int(Frame&)>& optimize_pose, const RelocalizationOptions& options) {
  PlaceCandidateOptions candidate_options;
  candidate_options.map_id = options.map_id;
  const std::vector<KeyFrame*> candidates = FindPlaceCandidates(frame.bow, database, map, candidate_options);
  const bool exclude_dynamic = options.exclude_dynamic;
  const auto& camera = frame.data().camera;
  for (KeyFrame* kf : candidates) {
    std::vector<MapPoint*> matches;
    if (SearchByBow(*kf, frame, matches, 0.75f) < 15) continue;

    Points3d world_points, bearings;
    std::vector<size_t> slots;
    for (size_t i = 0; i < matches.size(); ++i) {
      if (matches[i] == nullptr || matches[i]->is_bad() || (exclude_dynamic && matches[i]->IsDynamic()))
        continue;
      world_points.push_back(matches[i]->position());
      bearings.push_back(camera.Unproject(frame.features().keypoints[i].pixel.cast<double>()));
      slots.push_back(i);
    }
    PnpRansacOptions pnp_options;
    pnp_options.max_reprojection_error_px = 2.0 * std::sqrt(5.991);
    pnp_options.focal_length = camera.fx;
    pnp_options.seed = frame.id() ^ kf->id();
    const auto pnp = SolvePnpRansac(world_points, bearings, pnp_options);
    if (!pnp || pnp->num_inliers < 10) continue;

    frame.SetPose(pnp->camera_from_world);
    std::fill(frame.map_points.begin(), frame.map_points.end(), nullptr);
    std::fill(frame.outliers.begin(), frame.outliers.end(), false);
    for (size_t k = 0; k < slots.size(); ++k) {
      if (pnp->inliers[k]) frame.map_points[slots[k]] = matches[slots[k]];
    }
    int good = optimize_pose(frame);
    if (good < 10) continue;
    std::set<MapPoint*> found;
    for (size_t i = 0; i < frame.map_points.size(); ++i) {
      if (frame.outliers[i]) {
        frame.map_points[i] = nullptr;
        frame.outliers[i] = false;
      } else if (frame.map_points[i] != nullptr) {
        found.insert(frame.map_points[i]);
      }
    }
    if (good < 50) {
      // A guided search in the candidate's map points for more matches, then again with a tighter window.
      const int more = SearchFromKeyFrame(frame, *kf, found, 10.0f, 100);
      if (good + more >= 50) {
        good = optimize_pose(frame);
        if (good > 30 && good < 50) {
          found.clear();
          for (size_t i = 0; i < frame.map_points.size(); ++i) {
            if (frame.map_points[i] != nullptr && !frame.outliers[i]) found.insert(frame.map_points[i]);
          }
          const int extra = SearchFromKeyFrame(frame, *kf, found, 3.0f, 64);
          if (good + extra >= 50) {
            good = optimize_pose(frame);
          }
        }
        for (size_t i = 0; i < frame.map_points.size(); ++i) {
          if (frame.outliers[i]) {
            frame.map_points[i] = nullptr;
            frame.outliers[i] = false;
          }
        }
      }
    }
    if (good >= 50 && (!options.plausible || options.plausible(frame))) {
      frame.reference_keyframe = kf;
      return true;
    }
  }
  return false;
}

}  // namespace semslam
