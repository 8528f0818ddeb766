#pragma once
// What a run reports about the maps of its atlas (see map/map.h): run.json's "maps" section and frames.csv,
// the map and pose source of every frame.

#include <filesystem>
#include <nlohmann/json_fwd.hpp>

#include "semslam/semantics/semantic_outputs.h"
#include "semslam/system/slam_system.h"

namespace semslam {

// A loop or merge as run.json gives it: {"query_keyframe", "matched_keyframe", "timestamp" (the query's),
// "matched_timestamp", "matches", "scale"}; callers add what is particular to loops or merges.
nlohmann::json LoopEventJson(const LoopEvent& e);

// {"count", "started", "merges", "main_map", "frames_per_map": {id: frames}, "unmerged_frames",
//  "merge_events": [...], "sessions": [...]} after Finish().
nlohmann::json AtlasJson(const SlamSystem& slam);

// The final bundle adjustment's self-calibration per monocular map: [{"map", "accepted", "reason" (when not),
// "nominal": {fx, fy, cx, cy}, "refined": {fx, fy, cx, cy, k1, k2}, "plain_cost", "refined_cost"}] after
// Finish().
nlohmann::json IntrinsicsRefinementJson(const SlamSystem& slam);

// One line per frame of the run with a pose: frame, timestamp, map, source (tracked: tracked, relocalized
// or posed at a monocular initialization; predicted: the motion model's while lost), in_main_map (0/1: frames
// of maps never merged into the main one are 0), and the pose in its map (tx ty tz qx qy qz qw,
// world_from_camera as in TUM files). Written atomically.
void WriteFramesCsv(const std::filesystem::path& path, const SlamSystem& slam);
// The same for given poses (in_main_map: map_id == main_map).
void WriteFramesCsv(const std::filesystem::path& path, const std::vector<FramePose>& poses,
                    std::uint32_t main_map);
// Reads what WriteFramesCsv wrote (predicted frames marked). Throws InputError naming the file and line.
std::vector<FramePose> ReadFramesCsv(const std::filesystem::path& path);
// run.json's "classes": map points per class (by class key) and "unlabeled".
nlohmann::json ClassCountsJson(const ClassCounts& counts);
// timing.json: per timer {count, median_ms, mean_ms, p95_ms, max_ms, total_ms}.
nlohmann::json TimingJson(const TimingRegistry& timing);
// Every good map point of the atlas, with its label.
std::vector<SemanticPoint> SemanticPoints(const Map& map);

}  // namespace semslam
