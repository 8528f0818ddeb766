#pragma once
// Keyframes of the map that look like a query (Galvez-Lopez & Tardos 2012; Mur-Artal et al. 2015, sections
// V-VI), for relocalization and loop detection alike: the database's keyframes whose share of their words
// in common with the query is at least 80 % of the best share (and that score at least `min_score`) are
// scored; each one's score is accumulated with those of its scored covisible neighbours, and the best-scoring
// keyframe of every group whose accumulated score is at least 75 % of the best group's is a candidate, best
// group first.

#include <cstdint>
#include <optional>
#include <set>
#include <vector>

#include "semslam/map/map.h"
#include "semslam/place/bow_vector.h"
#include "semslam/place/keyframe_database.h"

namespace semslam {

struct PlaceCandidateOptions {
  double min_score = 0.0;
  std::set<std::uint64_t> excluded;           // keyframe ids never returned (the query and its neighbours)
  std::optional<std::uint32_t> map_id;        // only keyframes of this map (see map.h); none: of any map
  std::set<std::uint32_t> excluded_maps;      // no keyframe of these maps
  std::set<std::uint32_t> excluded_sessions;  // nor of these sessions
};

// Read lock on the map held by the caller.
std::vector<KeyFrame*> FindPlaceCandidates(const BowVector& query, const KeyFrameDatabase& database,
                                           const Map& map, const PlaceCandidateOptions& options = {});

}  // namespace semslam
