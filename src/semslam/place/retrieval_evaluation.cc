#include "semslam/place/retrieval_evaluation.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "semslam/core/error.h"
#include "semslam/place/keyframe_database.h"

namespace semslam {

void RetrievalOptions::Check() const {
  Require(database_every >= 1, "retrieval: database_every must be >= 1");
  Require(exclude_recent >= 0, "retrieval: exclude_recent must be >= 0");
  Require(same_place_distance > 0 && same_place_angle_deg > 0,
          "retrieval: same-place thresholds must be positive");
}

namespace {
double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}
}  // namespace

RetrievalResult EvaluateRetrieval(const Vocabulary& vocabulary,
                                  const std::vector<std::vector<Descriptor>>& descriptors,
                                  const std::vector<Eigen::Vector3d>& positions,
                                  const std::vector<Eigen::Vector3d>& directions,
                                  const RetrievalOptions& options) {
  options.Check();
  Require(descriptors.size() == positions.size() && positions.size() == directions.size(),
          "retrieval: one position and direction per frame needed");
  const double cos_limit = std::cos(options.same_place_angle_deg * std::numbers::pi / 180.0);
  auto same_place = [&](size_t a, size_t b) {
    return (positions[a] - positions[b]).norm() <= options.same_place_distance &&
           directions[a].normalized().dot(directions[b].normalized()) >= cos_limit;
  };
  KeyFrameDatabase database(vocabulary.size());
  std::vector<size_t> in_database;
  RetrievalResult result;
  std::vector<double> true_scores, other_scores, revisit_scores;
  std::vector<BowVector> bows(descriptors.size());
  for (size_t i = 0; i < descriptors.size(); ++i) bows[i] = vocabulary.Transform(descriptors[i]);
  for (size_t i = 0; i < descriptors.size(); ++i) {
    const size_t newest = i >= static_cast<size_t>(options.exclude_recent)
                              ? i - static_cast<size_t>(options.exclude_recent)
                              : 0;
    const bool any_old =
        !in_database.empty() && in_database.front() + static_cast<size_t>(options.exclude_recent) <= i;
    if (any_old) {
      DatabaseQueryOptions query;
      query.filter = [&](std::uint64_t id) {
        return id + static_cast<std::uint64_t>(options.exclude_recent) <= i;
      };
      const auto results = database.Query(bows[i], query);
      ++result.queries;
      bool revisit = false;
      for (const size_t j : in_database) {
        if (j > newest) break;
        if (same_place(i, j)) {
          revisit = true;
          break;
        }
      }
      const double best = results.empty() ? 0.0 : results[0].score;
      if (revisit) {
        ++result.revisits;
        revisit_scores.push_back(best);
        for (size_t k = 0; k < std::min<size_t>(5, results.size()); ++k) {
          if (!same_place(i, static_cast<size_t>(results[k].id))) continue;
          if (k == 0) {
            ++result.top1;
            true_scores.push_back(best);
          }
          ++result.top5;
          break;
        }
      } else {
        other_scores.push_back(best);
      }
    }
    if (i % static_cast<size_t>(options.database_every) == 0) {
      database.Add(i, bows[i]);
      in_database.push_back(i);
    }
  }
  result.median_true_score = Median(true_scores);
  result.median_other_score = Median(other_scores);
  const double revisit_median = Median(revisit_scores);
  for (const double s : other_scores) result.false_top1 += s > revisit_median && !revisit_scores.empty();
  return result;
}

}  // namespace semslam
