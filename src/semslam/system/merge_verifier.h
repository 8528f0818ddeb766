#pragma once
// Which merges place recognition may make between saved maps (system/session_merge.h), and between the maps
// of a stereo run (system/slam_system.h).
#include <cstdint>
#include <map>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include "semslam/geometry/sim3.h"
#include "semslam/map/keyframe.h"

namespace semslam {

// A place seen on two drives passes loop closing's geometric checks; so does a look-alike (towns repeat their
// facades), and between maps that share no odometry nothing else would tell. So: between two maps in the
// world
// (`world_maps`, which the caller keeps current), the merge must agree with where their GPS placed them;
// otherwise a second place, out of sight of the first (no covisibility), must give the same transform, found
// in either direction (a place of a in b, or one of b in a). A loop between two drives of one merged map (a
// place shared beyond the merge's seam) is held to the same: a second place between the same two drives must
// confirm its correction. Counts what it refused or kept waiting.
class MergeVerifier {
 public:
  explicit MergeVerifier(const std::set<std::uint32_t>& world_maps) : world_maps_(world_maps) {}

  bool operator()(const KeyFrame& current, const KeyFrame& matched, const Sim3d& matched_from_current_map);

  int rejected() const { return rejected_; }

 private:
  static constexpr double kMaxWorldShiftM = 10.0;  // GPS σ of metres, a fused map's error of a few
  static constexpr double kMaxWorldTurnDeg = 10.0;
  static constexpr double kMaxWorldLogScale = 0.1;
  static constexpr double kMaxRelativeDisagreement = 0.1;
  static constexpr double kMaxTurnDisagreementDeg = 5.0;
  struct Proposal {
    const KeyFrame* keyframe;  // the place, and the keyframe it was found in
    const KeyFrame* matched;
    std::uint32_t from;  // its keyframe's map (its session, for a loop)
    Sim3d transform;     // matched_from_current_map
  };
  // (loop, a, b), a < b: the maps a and b, or for a loop the sessions a and b.
  using Pair = std::tuple<bool, std::uint32_t, std::uint32_t>;
  const std::set<std::uint32_t>& world_maps_;
  std::map<Pair, std::vector<Proposal>> proposals_;
  int rejected_ = 0;
};

}  // namespace semslam
