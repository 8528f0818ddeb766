#include "semslam/map/place_candidates.h"

#include <algorithm>
#include <map>

namespace semslam {

std::vector<KeyFrame*> FindPlaceCandidates(const BowVector& query, const KeyFrameDatabase& database,
                                           const Map& map, const PlaceCandidateOptions& options) {
  struct Scored {
    double word_share = 0.0;
    double score = 0.0;
  };
  std::map<KeyFrame*, Scored, ById> found;
  double max_share = 0.0;
  for (const DatabaseResult& r : database.Query(query)) {
    if (options.excluded.count(r.id)) continue;
    KeyFrame* kf = map.KeyFrameById(r.id);
    if (kf == nullptr || kf->is_bad() || (options.map_id && kf->map_id() != *options.map_id) ||
        options.excluded_maps.count(kf->map_id()) || options.excluded_sessions.count(kf->session()))
      continue;
    // The share of the keyframe's words, not their number: a keyframe with more words shares more by chance
    // alone, and a map's first keyframes have twice the features (for its initialization).
    const double share =
        static_cast<double>(r.shared_words) / static_cast<double>(std::max<size_t>(kf->bow.size(), 1));
    found[kf] = {share, r.score};
    max_share = std::max(max_share, share);
  }
  const double min_share = 0.8 * max_share;
  std::map<KeyFrame*, double, ById> scored;
  for (const auto& [kf, s] : found) {
    if (s.word_share > min_share && s.score >= options.min_score) scored[kf] = s.score;
  }
  // Each keyframe's score accumulated with its scored covisible neighbours; the best keyframe of each group.
  std::vector<std::pair<double, KeyFrame*>> groups;
  double best_accumulated = 0.0;
  for (const auto& [kf, score] : scored) {
    double accumulated = score, best_score = score;
    KeyFrame* best = kf;
    for (KeyFrame* neighbour : kf->BestCovisibles(10)) {
      const auto it = scored.find(neighbour);
      if (it == scored.end()) continue;
      accumulated += it->second;
      if (it->second > best_score) {
        best_score = it->second;
        best = neighbour;
      }
    }
    groups.emplace_back(accumulated, best);
    best_accumulated = std::max(best_accumulated, accumulated);
  }
  std::stable_sort(groups.begin(), groups.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<KeyFrame*> candidates;
  std::set<KeyFrame*, ById> seen;
  for (const auto& [accumulated, kf] : groups) {
    if (accumulated < 0.75 * best_accumulated) break;
    if (seen.insert(kf).second) candidates.push_back(kf);
  }
  return candidates;
}

}  // namespace semslam
