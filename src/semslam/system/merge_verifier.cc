#include "semslam/system/merge_verifier.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace semslam {

bool MergeVerifier::operator()(const KeyFrame& current, const KeyFrame& matched,
                               const Sim3d& matched_from_current_map) {
  const Eigen::Vector3d centre = current.world_from_camera().translation;
  const bool loop = current.map_id() == matched.map_id();
  const std::string what =
      loop ? fmt::format("loop between sessions {} and {} of map {}", current.session(), matched.session(),
                         current.map_id())
           : fmt::format("merge of map {} into map {}", current.map_id(), matched.map_id());
  if (world_maps_.count(current.map_id()) && world_maps_.count(matched.map_id())) {
    const double shift_m = (matched_from_current_map * centre - centre).norm();
    const double turn_deg = Eigen::AngleAxisd(matched_from_current_map.rotation).angle() * 180.0 / M_PI;
    const bool agrees = shift_m <= kMaxWorldShiftM && turn_deg <= kMaxWorldTurnDeg &&
                        std::abs(std::log(matched_from_current_map.scale)) <= kMaxWorldLogScale;
    spdlog::info("{}: {} with the GPS placement (it moves keyframe {} by {:.1f} m, {:.1f} deg, scale {:.3f})",
                 what, agrees ? "agrees" : "disagrees", current.id(), shift_m, turn_deg,
                 matched_from_current_map.scale);
    if (!agrees) ++rejected_;
    return agrees;
  }
  // Places of either direction count: a place of map (or drive) a found in b, and one of b found in a.
  const std::uint32_t from = loop ? current.session() : current.map_id();
  const std::uint32_t to = loop ? matched.session() : matched.map_id();
  std::vector<Proposal>& earlier = proposals_[Pair{loop, std::min(from, to), std::max(from, to)}];
  const std::vector<KeyFrame*>& covisibles = current.Covisibles();
  const auto in_sight = [&](const KeyFrame* kf) {
    return kf == &current || std::find(covisibles.begin(), covisibles.end(), kf) != covisibles.end();
  };
  for (const Proposal& p : earlier) {
    // The earlier place as this one's direction sees it: its transform, and where it lies in the current
    // keyframe's map (a loop's two drives share one).
    const bool same_direction = p.from == from;
    const KeyFrame* place = same_direction ? p.keyframe : p.matched;
    if (p.keyframe->is_bad() || p.matched->is_bad() || in_sight(place)) continue;
    const Sim3d earlier_transform = same_direction ? p.transform : p.transform.Inverse();
    // Both transforms applied to both places: how far apart they put them, against the distance between
    // the places (the matched map's units).
    const Eigen::Vector3d other = same_direction || loop
                                      ? p.keyframe->world_from_camera().translation
                                      : p.transform * p.keyframe->world_from_camera().translation;
    const double span = (matched_from_current_map * centre - matched_from_current_map * other).norm();
    const double disagreement =
        std::max((matched_from_current_map * centre - earlier_transform * centre).norm(),
                 (matched_from_current_map * other - earlier_transform * other).norm());
    const double turn_deg =
        Eigen::AngleAxisd(matched_from_current_map.rotation * earlier_transform.rotation.inverse()).angle() *
        180.0 / M_PI;
    if (span > 0.0 && disagreement <= kMaxRelativeDisagreement * span &&
        turn_deg <= kMaxTurnDisagreementDeg) {
      spdlog::info(
          "{}: keyframes {} and {}, out of sight of each other, agree ({:.1f} % of the {:.1f} units between "
          "them, {:.1f} deg)",
          what, p.keyframe->id(), current.id(), 100.0 * disagreement / span, span, turn_deg);
      proposals_.clear();
      return true;
    }
  }
  spdlog::info("{} at keyframe {}: kept until another place confirms it", what, current.id());
  earlier.push_back({&current, &matched, from, matched_from_current_map});
  ++rejected_;
  return false;
}

}  // namespace semslam
