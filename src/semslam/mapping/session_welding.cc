#include "semslam/mapping/session_welding.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/map/map_matcher.h"

namespace semslam {

void SessionWeldingOptions::Check() const {
  Require(neighbour_radius_spacings > 0, "session welding: neighbour_radius_spacings must be positive");
  Require(max_heading_difference_deg > 0 && max_heading_difference_deg <= 180,
          "session welding: max_heading_difference_deg must be in (0, 180]");
  Require(max_neighbours > 0, "session welding: max_neighbours must be positive");
  Require(fuse_radius_px > 0, "session welding: fuse_radius_px must be positive");
}

namespace {

// The median distance between a drive's consecutive keyframes: the map's unit where the drive was (a
// monocular map's scale is its own).
double MedianSpacing(const std::vector<KeyFrame*>& keyframes) {
  std::vector<double> steps;
  for (size_t i = 1; i < keyframes.size(); ++i)
    steps.push_back((keyframes[i]->center() - keyframes[i - 1]->center()).norm());
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  return steps[steps.size() / 2];
}

Eigen::Vector3d ViewingDirection(const KeyFrame& kf) {
  return kf.world_from_camera().rotation * Eigen::Vector3d::UnitZ();
}

}  // namespace

SessionWeldingSummary WeldSessions(Map& map, std::uint32_t map_id, const SessionWeldingOptions& options) {
  options.Check();
  SessionWeldingSummary summary;
  std::map<std::uint32_t, std::vector<KeyFrame*>> by_session;  // each in id order
  for (KeyFrame* kf : map.KeyFramesOfMap(map_id)) {
    if (!kf->is_bad()) by_session[kf->session()].push_back(kf);
  }
  if (by_session.size() < 2) return summary;
  std::map<std::uint32_t, double> radius;
  for (const auto& [session, keyframes] : by_session)
    radius[session] = options.neighbour_radius_spacings * MedianSpacing(keyframes);
  const double min_cos = std::cos(options.max_heading_difference_deg * M_PI / 180.0);

  for (const auto& [session, keyframes] : by_session) {
    const double r = radius[session];
    if (!(r > 0)) continue;
    for (KeyFrame* kf : keyframes) {
      if (kf->is_bad()) continue;
      const Eigen::Vector3d center = kf->center(), heading = ViewingDirection(*kf);
      std::vector<std::pair<double, KeyFrame*>> near;
      for (const auto& [other_session, others] : by_session) {
        if (other_session == session) continue;
        for (KeyFrame* other : others) {
          if (other->is_bad()) continue;
          const double d = (other->center() - center).norm();
          if (d <= r && ViewingDirection(*other).dot(heading) >= min_cos) near.emplace_back(d, other);
        }
      }
      if (near.empty()) continue;
      const size_t keep = std::min(near.size(), static_cast<size_t>(options.max_neighbours));
      std::partial_sort(near.begin(), near.begin() + static_cast<long>(keep), near.end(),
                        [](const auto& a, const auto& b) {
                          return a.first != b.first ? a.first < b.first : a.second->id() < b.second->id();
                        });
      std::vector<MapPoint*> points;
      std::set<const MapPoint*> offered;
      for (size_t i = 0; i < keep; ++i) {
        for (MapPoint* p : near[i].second->map_points()) {
          if (p != nullptr && !p->is_bad() && offered.insert(p).second) points.push_back(p);
        }
      }
      ++summary.keyframes;
      summary.fused_observations += static_cast<size_t>(Fuse(kf, points, options.fuse_radius_px));
    }
  }
  // Points that another took the place of are gone; the survivors see with their new observers.
  for (MapPoint* p : map.MapPointsOfMap(map_id)) {
    if (p->is_bad()) {
      map.EraseMapPoint(p);
    } else {
      p->UpdateDescriptor();
      p->UpdateNormalAndDepth();
    }
  }
  for (const auto& [session, keyframes] : by_session) {
    for (KeyFrame* kf : keyframes) {
      if (!kf->is_bad()) kf->UpdateConnections();
    }
  }
  return summary;
}

}  // namespace semslam
