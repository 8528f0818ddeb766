#include "semslam/map/keyframe_matches.h"

#include <algorithm>

namespace semslam {

std::vector<KeyFramePointMatch> MatchesInCameraFrames(const KeyFrame& kf1, const KeyFrame& kf2,
                                                      const std::vector<MapPoint*>& matches12) {
  std::vector<KeyFramePointMatch> found;
  const size_t slots = std::min(matches12.size(), kf1.num_features());
  for (size_t i = 0; i < slots; ++i) {
    const MapPoint* p1 = kf1.map_point(static_cast<int>(i));
    const MapPoint* p2 = matches12[i];
    if (p1 == nullptr || p2 == nullptr || p1->is_bad() || p2->is_bad()) continue;
    const int i2 = p2->IndexIn(&kf2);
    if (i2 < 0) continue;
    found.push_back({i, static_cast<size_t>(i2), kf1.camera_from_world() * p1->position(),
                     kf2.camera_from_world() * p2->position()});
  }
  return found;
}

}  // namespace semslam
