#include "semslam/system/merge_places.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <map>
#include <utility>
#include <vector>

#include "semslam/core/interrupt.h"
#include "semslam/core/progress.h"
#include "semslam/loop/loop_closer.h"
#include "semslam/map/map.h"
#include "semslam/system/merge_verifier.h"
#include "semslam/system/slam_system.h"

namespace semslam {
namespace {

// Merges maps until a pass over every map merges nothing.
void MergeMapsByPlaces(SlamSystem& slam, MergeVerifier& verifier, std::set<std::uint32_t>& world_maps,
                       ProgressReporter& progress, size_t& examined, size_t to_examine,
                       PlaceRecognitionSummary& summary) {
  Map& map = slam.map();
  std::vector<std::uint32_t> map_ids;
  {
    auto lock = map.ReadLock();
    map_ids = map.MapIds();
  }
  for (bool merged = true; merged && map_ids.size() > 1 && !summary.interrupted;) {
    merged = false;
    std::stable_partition(map_ids.begin(), map_ids.end(),
                          [&](std::uint32_t id) { return !world_maps.count(id); });
    for (const std::uint32_t map_id : map_ids) {
      std::vector<KeyFrame*> keyframes;
      LoopCloser::PlaceExclusions excluded;
      excluded.maps = {map_id};
      {
        auto lock = map.ReadLock();
        keyframes = map.KeyFramesOfMap(map_id);
        if (world_maps.count(map_id)) {
          for (const std::uint32_t other : map.MapIds()) {
            if (!world_maps.count(other)) excluded.maps.insert(other);
          }
        }
      }
      slam.loop_closer().ForgetCandidates();
      for (KeyFrame* kf : keyframes) {
        if (InterruptRequested()) {
          summary.interrupted = true;
          break;
        }
        progress.Update(std::min(++examined, to_examine),
                        fmt::format("map {}, {} merges", map_id, summary.merges));
        if (kf->is_bad() || !slam.loop_closer().ProcessKeyFrame(kf, excluded, std::ref(verifier))) continue;
        ++summary.merges;
        merged = true;
        if (world_maps.erase(map_id)) world_maps.insert(kf->map_id());
        break;
      }
      if (merged || summary.interrupted) break;
    }
    auto lock = map.ReadLock();
    map_ids = map.MapIds();
  }
}

// Loops between the drives of each map out of the world that holds more than one: each drive's keyframes, in
// order, against the other drives' keyframes of its map (its own places were its run's to close).
void CloseLoopsBetweenSessions(SlamSystem& slam, MergeVerifier& verifier,
                               const std::set<std::uint32_t>& world_maps, ProgressReporter& progress,
                               size_t& examined, size_t to_examine, PlaceRecognitionSummary& summary) {
  Map& map = slam.map();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> drives;  // (map, session), a map's drives together
  std::set<std::uint32_t> all_maps;
  {
    auto lock = map.ReadLock();
    std::map<std::uint32_t, std::set<std::uint32_t>> sessions_of_map;
    for (const KeyFrame* kf : map.KeyFrames()) {
      if (!kf->is_bad()) sessions_of_map[kf->map_id()].insert(kf->session());
    }
    for (const auto& [map_id, sessions] : sessions_of_map) {
      all_maps.insert(map_id);
      if (sessions.size() < 2 || world_maps.count(map_id)) continue;
      for (const std::uint32_t session : sessions) drives.emplace_back(map_id, session);
    }
  }
  for (const auto& [map_id, session] : drives) {
    LoopCloser::PlaceExclusions excluded;
    excluded.maps = all_maps;
    excluded.maps.erase(map_id);
    excluded.sessions = {session};
    std::vector<KeyFrame*> keyframes;
    {
      auto lock = map.ReadLock();
      for (KeyFrame* kf : map.KeyFramesOfMap(map_id)) {
        if (kf->session() == session) keyframes.push_back(kf);
      }
    }
    slam.loop_closer().ForgetCandidates();
    for (KeyFrame* kf : keyframes) {
      if (InterruptRequested()) {
        summary.interrupted = true;
        return;
      }
      progress.Update(
          std::min(++examined, to_examine),
          fmt::format("map {}, session {}: {} loops between drives", map_id, session, summary.session_loops));
      if (!kf->is_bad() && slam.loop_closer().ProcessKeyFrame(kf, excluded, std::ref(verifier)))
        ++summary.session_loops;
    }
  }
}

}  // namespace

PlaceRecognitionSummary RecognizePlacesAcrossDrives(SlamSystem& slam, std::set<std::uint32_t>& world_maps,
                                                    const PlaceRecognitionOptions& options) {
  PlaceRecognitionSummary summary;
  size_t to_examine = 0;
  {
    auto lock = slam.map().ReadLock();
    // A pass to merge, and one for loops between drives.
    to_examine = (options.loops_between_drives ? 2 : 1) * slam.map().NumKeyFrames();
  }
  ProgressReporter progress("merge", to_examine, options.show_progress);
  MergeVerifier verifier(world_maps);
  size_t examined = 0;
  MergeMapsByPlaces(slam, verifier, world_maps, progress, examined, to_examine, summary);
  if (options.loops_between_drives && !summary.interrupted)
    CloseLoopsBetweenSessions(slam, verifier, world_maps, progress, examined, to_examine, summary);
  progress.Finish(fmt::format("{} maps merged by place recognition, {} loops between drives", summary.merges,
                              summary.session_loops));
  summary.not_confirmed = verifier.rejected();
  return summary;
}

}  // namespace semslam
