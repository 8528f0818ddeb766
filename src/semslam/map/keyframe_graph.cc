#include "semslam/map/keyframe_graph.h"

#include <functional>
#include <limits>
#include <queue>
#include <unordered_map>
#include <utility>
#include <vector>

namespace semslam {

double KeyFrameGraphDistance(const KeyFrame& from, const KeyFrame& to, int min_covisibility_weight) {
  using Entry = std::pair<double, const KeyFrame*>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  std::unordered_map<const KeyFrame*, double> distance;
  distance[&from] = 0.0;
  open.emplace(0.0, &from);
  while (!open.empty()) {
    // Plain copies: clang 14 cannot capture structured bindings in the lambda below.
    const double d = open.top().first;
    const KeyFrame* kf = open.top().second;
    open.pop();
    if (kf == &to) return d;
    if (d > distance[kf]) continue;  // a shorter chain reached it already
    auto relax = [&](const KeyFrame* next) {
      if (next == nullptr || next->is_bad() || next->map_id() != from.map_id()) return;
      const double through = d + (next->center() - kf->center()).norm();
      const auto it = distance.find(next);
      if (it != distance.end() && it->second <= through) return;
      distance[next] = through;
      open.emplace(through, next);
    };
    relax(kf->parent());
    for (const KeyFrame* child : kf->children()) relax(child);
    for (const KeyFrame* other : kf->loop_edges()) relax(other);
    for (const KeyFrame* other : kf->CovisiblesWithWeightAtLeast(min_covisibility_weight)) relax(other);
  }
  return std::numeric_limits<double>::infinity();
}

}  // namespace semslam
