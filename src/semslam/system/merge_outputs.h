#pragma once
// What `semslam merge` writes of the merged atlas besides map.semslam and run.json (session_merge.h, step 7):
// each session's frames in the merged map, the semantic map and the geographic outputs of the main map, and
// how far each drive lies from its truth alone and in one alignment of the whole city.

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "semslam/geo/georeference.h"
#include "semslam/map/map.h"
#include "semslam/report/geo_outputs.h"
#include "semslam/semantics/semantic_outputs.h"
#include "semslam/system/merge_session_frames.h"

namespace semslam {

struct MergeOutputOptions {
  std::filesystem::path folder;  // the merge's output folder
  std::uint32_t main_map = 0;    // the map the outputs describe
  bool stereo = false;
  FrameScale frame_scale = FrameScale::kKeyFrame;
  // Set when the main map is in the world: its frame is then ENU about this origin.
  std::optional<EnuFrame> world;
  std::vector<std::filesystem::path> catalogues;  // the runs' landmark catalogues
};

struct MergeOutputs {
  nlohmann::json sessions = nlohmann::json::array();  // run.json's maps.sessions
  std::optional<double> city_ate;  // every drive with a truth, in one alignment of them all
  std::vector<SemanticPoint> semantic_points;
  GeoOutputs geo;
  nlohmann::json landmark_evaluation = nullptr;  // the synthetic town's landmarks against their truth
};

// Writes sessions/<id>-<name>/ for each session (trajectory.tum, keyframes.tum and frames.csv in the main
// map's frame; trajectory_wgs84.csv in the world), semantic_map.ply and the geographic outputs
// (report/geo_outputs.h: landmarks, topology, objects, plots), and fills each session's `frames`. Takes the
// map's read lock.
MergeOutputs WriteMergeOutputs(const Map& map, std::vector<SessionRecord>& sessions,
                               const MergeOutputOptions& options);

}  // namespace semslam
