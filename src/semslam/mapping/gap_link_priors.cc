#include "semslam/mapping/gap_link_priors.h"

#include <cmath>
#include <optional>
#include <unordered_map>

namespace semslam {

namespace {

// The prior's sigmas: a share of the ends' distance, and an angle. The observations leave the ends' relative
// pose free, so any sigma holds it; these let a BA still move it where points do tie the two sides.
constexpr double kTranslationSigmaShare = 0.05;
constexpr double kRotationSigmaRad = M_PI / 180.0;

}  // namespace

std::unordered_set<const KeyFrame*> GapLinkEnds(const Map& map) {
  std::unordered_set<const KeyFrame*> ends;
  for (const GapLink& link : map.gap_links()) {
    const std::optional<GapEdge> edge = ResolveGapLink(link);
    if (!edge) continue;
    ends.insert(edge->before);
    ends.insert(edge->after);
  }
  return ends;
}

void AddGapLinkPriors(const Map& map, std::vector<KeyFrame*>* keyframes, BundleAdjustmentProblem* problem) {
  std::unordered_map<const KeyFrame*, int> index;
  for (size_t i = 0; i < keyframes->size(); ++i) index[(*keyframes)[i]] = static_cast<int>(i);
  auto pose_of = [&](KeyFrame* kf) {
    const auto it = index.find(kf);
    if (it != index.end()) return it->second;
    const int added = static_cast<int>(keyframes->size());
    keyframes->push_back(kf);
    problem->camera_from_world.push_back(kf->camera_from_world());
    problem->pose_fixed.push_back(true);
    index[kf] = added;
    return added;
  };
  for (const GapLink& link : map.gap_links()) {
    const std::optional<GapEdge> edge = ResolveGapLink(link);
    if (!edge || edge->before->map_id() != edge->after->map_id()) continue;
    if (!index.count(edge->before) && !index.count(edge->after)) continue;
    const Rigid3d before_from_after = edge->before->camera_from_world() * edge->after->world_from_camera();
    const double distance = before_from_after.translation.norm();
    if (!(distance > 0.0)) continue;
    BundleAdjustmentPosePrior prior;
    prior.a = pose_of(edge->before);
    prior.b = pose_of(edge->after);
    prior.a_from_b = before_from_after;
    prior.sigma_translation = kTranslationSigmaShare * distance;
    prior.sigma_rotation = kRotationSigmaRad;
    problem->pose_priors.push_back(prior);
  }
}

}  // namespace semslam
