#include "semslam/system/atlas_georeference.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <unordered_map>

#include "semslam/core/error.h"
#include "semslam/mapping/map_georeference.h"
#include "semslam/system/slam_system.h"

namespace semslam {

void AtlasGeoreferenceOptions::Check() const {
  fusion.Check();
  Require(!time_offset_s || std::isfinite(*time_offset_s), "GPS time offset must be finite");
}

namespace {

// Places one map: the fusion's keyframe poses (or the one similarity's), for MoveMapIntoWorld.
struct Placement {
  std::unordered_map<std::uint64_t, Sim3d> world_from_keyframe;
  Sim3d world_from_map;
};

std::optional<Placement> PlaceMap(const std::vector<FramePose>& frames,
                                  const std::vector<FramePose>& keyframes,
                                  const std::vector<FusionEdge>& edges, const GpsLog& log,
                                  const EnuFrame& enu, const std::optional<Sim3d>& known,
                                  const GpsFusionOptions& fusion, bool fuse,
                                  MapGeoreferenceSummary& summary) {
  Placement placement;
  std::optional<GpsAlignment> alignment;
  if (fuse) {
    GpsFusionInput input{keyframes, frames, edges, log.fixes, known};
    const std::optional<GpsFusionResult> result = FuseGps(input, enu, fusion);
    if (!result) return std::nullopt;
    for (size_t i = 0; i < keyframes.size(); ++i) {
      placement.world_from_keyframe[static_cast<std::uint64_t>(keyframes[i].keyframe_id)] =
          result->keyframe_enu_from_camera[i];
    }
    placement.world_from_map = result->georeference.enu_from_map;
    alignment = result->prealignment;
    summary.gps_samples = result->samples;
    summary.gps_inliers = result->inliers;
    summary.inliers = result->num_inliers;
    summary.fit_rmse_m = result->inlier_rmse_m;
  } else {
    std::vector<GpsSample> samples = SampleGpsPairs(Positions(frames), log.fixes, enu, fusion.sampling);
    if (known) {
      if (static_cast<int>(samples.size()) < fusion.alignment.min_samples) return std::nullopt;
      alignment = EvaluateAlignment(*known, samples, fusion.alignment);
    } else {
      alignment = AlignMapToGps(samples, fusion.alignment);
    }
    if (!alignment) return std::nullopt;
    for (const FramePose& k : keyframes) {
      placement.world_from_keyframe[static_cast<std::uint64_t>(k.keyframe_id)] =
          alignment->enu_from_map * Sim3d(k.world_from_camera);
    }
    placement.world_from_map = alignment->enu_from_map;
    summary.gps_samples = std::move(samples);
    summary.gps_inliers = alignment->inliers;
    summary.inliers = alignment->num_inliers;
    summary.fit_rmse_m = alignment->inlier_rmse_m;
  }
  summary.samples = static_cast<int>(summary.gps_samples.size());
  summary.single_similarity_rmse_m = alignment->inlier_rmse_m;
  summary.roll_from_cameras = alignment->roll_from_camera_down;
  for (const FramePose& f : frames) {
    summary.single_similarity_frames.emplace_back(f.frame_index,
                                                  alignment->enu_from_map * f.world_from_camera.translation);
  }
  return placement;
}

}  // namespace

AtlasGeoreference GeoreferenceAtlas(SlamSystem& slam, const GpsLog& log,
                                    const std::map<std::uint32_t, Georeference>& known,
                                    const AtlasGeoreferenceOptions& options) {
  options.Check();
  AtlasGeoreference out;
  if (log.fixes.empty()) return out;
  const EnuFrame enu = known.empty() ? MakeEnuFrame(log) : known.begin()->second.enu_frame;
  out.enu = enu;
  GpsFusionOptions fusion = options.fusion;
  {
    std::vector<double> times;
    for (const FramePose& f : slam.AllFramePoses()) times.push_back(f.timestamp);
    fusion.sampling.time_offset_s = options.time_offset_s.value_or(GuessTimeOffset(log.fixes, times));
    out.time_offset_s = fusion.sampling.time_offset_s;
  }
  std::vector<std::uint32_t> map_ids;
  {
    auto lock = slam.map().ReadLock();
    map_ids = slam.map().MapIds();
  }
  for (const std::uint32_t map_id : map_ids) {
    MapGeoreferenceSummary& m = out.maps.emplace_back();
    m.map_id = map_id;
    const std::vector<FramePose> frames = slam.FramePoses(map_id);
    const std::vector<FramePose> keyframes = slam.KeyFramePoses(map_id, /*all_sessions=*/false);
    m.frames = frames.size();
    m.keyframes = keyframes.size();
    if (frames.empty() || keyframes.empty()) {
      m.reason = "no frame of this run is in it";
      continue;
    }
    std::optional<Sim3d> enu_from_map;
    if (const auto it = known.find(map_id); it != known.end()) {
      enu_from_map = EnuFromEnu(enu, it->second.enu_frame) * it->second.enu_from_map;
    }
    const std::optional<Placement> placement = PlaceMap(frames, keyframes, slam.KeyFrameEdges(keyframes), log,
                                                        enu, enu_from_map, fusion, options.fuse, m);
    if (!placement) {
      m.samples = static_cast<int>(SampleGpsPairs(Positions(frames), log.fixes, enu, fusion.sampling).size());
      m.reason =
          m.samples < fusion.alignment.min_samples
              ? fmt::format("{} fixes on its frames, {} needed", m.samples, fusion.alignment.min_samples)
              : "its fixes do not place it (on one line with no level camera to set the roll about it, "
                "or fewer than 3 agree)";
      spdlog::info("map {} stays out of the world: {}", map_id, m.reason);
      continue;
    }
    {
      auto lock = slam.map().WriteLock();
      MoveMapIntoWorld(slam.map(), map_id, placement->world_from_keyframe, placement->world_from_map);
    }
    m.in_world = true;
    spdlog::info("map {} is in the world: {} of {} fixes kept, {:.2f} m RMSE (one similarity: {:.2f} m){}",
                 map_id, m.inliers, m.samples, m.fit_rmse_m, m.single_similarity_rmse_m,
                 m.roll_from_cameras ? "; on (or near) one line, the roll about it from its cameras" : "");
  }

  // Maps in the world share its frame: the largest takes the others in.
  std::vector<MapGeoreferenceSummary*> placed;
  for (MapGeoreferenceSummary& m : out.maps) {
    if (m.in_world) placed.push_back(&m);
  }
  std::stable_sort(placed.begin(), placed.end(),
                   [](const auto* a, const auto* b) { return a->frames > b->frames; });
  for (size_t i = 0; i < placed.size(); ++i) {
    if (i == 0 || !options.join) {
      out.world_maps.push_back(placed[i]->map_id);
      continue;
    }
    auto lock = slam.map().WriteLock();
    slam.map().MergeMapInto(placed[i]->map_id, placed[0]->map_id);
    placed[i]->joined_into = placed[0]->map_id;
    spdlog::info("map {} joined map {} in the world through the GPS", placed[i]->map_id, placed[0]->map_id);
  }
  return out;
}

}  // namespace semslam
