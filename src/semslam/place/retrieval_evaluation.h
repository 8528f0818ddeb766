#pragma once
// How well a vocabulary recognizes places: along a sequence with known poses, every frame queries a
// database of earlier frames (recent frames excluded, as loop detection excludes the covisible ones), and
// the best-scoring database frame should show the same place (close by, looking the same way) whenever the
// database holds one.

#include <Eigen/Core>
#include <vector>

#include "semslam/features/orb_types.h"
#include "semslam/place/vocabulary.h"

namespace semslam {

struct RetrievalOptions {
  int database_every = 5;    // every n-th frame enters the database (as keyframes would)
  int exclude_recent = 100;  // database frames less than this many frames before the query are skipped
  double same_place_distance = 5.0;    // metres between camera centres
  double same_place_angle_deg = 30.0;  // between viewing directions
  void Check() const;
};

struct RetrievalResult {
  int queries = 0;     // frames that queried a non-empty database
  int revisits = 0;    // queries for which the database held the same place
  int top1 = 0;        // revisits whose best result was the same place
  int top5 = 0;        // revisits with the same place among the five best
  int false_top1 = 0;  // queries without a revisit whose best result still scored above the revisits' median
  double median_true_score = 0.0;   // best score of a right top-1 result, median over revisits
  double median_other_score = 0.0;  // best score of queries without a revisit, median
  double Top1Rate() const { return revisits > 0 ? static_cast<double>(top1) / revisits : 0.0; }
  double Top5Rate() const { return revisits > 0 ? static_cast<double>(top5) / revisits : 0.0; }
};

// `descriptors[i]`, `positions[i]` (camera centre, metres) and `directions[i]` (optical axis, unit) of frame
// i, in sequence order.
RetrievalResult EvaluateRetrieval(const Vocabulary& vocabulary,
                                  const std::vector<std::vector<Descriptor>>& descriptors,
                                  const std::vector<Eigen::Vector3d>& positions,
                                  const std::vector<Eigen::Vector3d>& directions,
                                  const RetrievalOptions& options = {});

}  // namespace semslam
