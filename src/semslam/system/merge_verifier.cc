#include "semslam/system/merge_verifier.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>

namespace semslam {

bool MergeVerifier::operator()(const KeyFrame& current, const KeyFrame& matched,
                               const Sim3d& matched_from_current_map) {
  const Eigen::Vector3d centre = current.world_from_camera().translation;
  if (world_maps_.count(current.map_id()) && world_maps_.count(matched.map_id())) {
    const double shift_m = (matched_from_current_map * centre - centre).norm();
    const double turn_deg = Eigen::AngleAxisd(matched_from_current_map.rotation).angle() * 180.0 / M_PI;
    const bool agrees = shift_m <= kMaxWorldShiftM && turn_deg <= kMaxWorldTurnDeg &&
                        std::abs(std::log(matched_from_current_map.scale)) <= kMaxWorldLogScale;
    spdlog::info(
        "merge of map {} into map {}: {} with their GPS placement (it moves keyframe {} by {:.1f} m, "
        "{:.1f} deg, scale {:.3f})",
        current.map_id(), matched.map_id(), agrees ? "agrees" : "disagrees", current.id(), shift_m, turn_deg,
        matched_from_current_map.scale);
    if (!agrees) ++rejected_;
    return agrees;
  }
  const std::pair<std::uint32_t, std::uint32_t> pair{current.map_id(), matched.map_id()};
  std::vector<Proposal>& earlier = proposals_[pair];
  for (const Proposal& p : earlier) {
    const std::vector<KeyFrame*>& covisibles = current.Covisibles();
    if (p.keyframe == &current || p.keyframe->is_bad() ||
        std::find(covisibles.begin(), covisibles.end(), p.keyframe) != covisibles.end()) {
      continue;
    }
    // Both transforms applied to both places: how far apart they put them, against the distance between
    // the places (the matched map's units).
    const Eigen::Vector3d other = p.keyframe->world_from_camera().translation;
    const double span = (matched_from_current_map * centre - matched_from_current_map * other).norm();
    const double disagreement = std::max((matched_from_current_map * centre - p.transform * centre).norm(),
                                         (matched_from_current_map * other - p.transform * other).norm());
    const double turn_deg =
        Eigen::AngleAxisd(matched_from_current_map.rotation * p.transform.rotation.inverse()).angle() *
        180.0 / M_PI;
    if (span > 0.0 && disagreement <= kMaxRelativeDisagreement * span &&
        turn_deg <= kMaxTurnDisagreementDeg) {
      spdlog::info(
          "merge of map {} into map {}: keyframes {} and {}, out of sight of each other, agree ({:.1f} % "
          "of the {:.1f} units between them, {:.1f} deg)",
          current.map_id(), matched.map_id(), p.keyframe->id(), current.id(), 100.0 * disagreement / span,
          span, turn_deg);
      proposals_.clear();
      return true;
    }
  }
  spdlog::info("merge of map {} into map {} at keyframe {}: kept until another place confirms it",
               current.map_id(), matched.map_id(), current.id());
  earlier.push_back({&current, matched_from_current_map});
  ++rejected_;
  return false;
}

}  // namespace semslam
