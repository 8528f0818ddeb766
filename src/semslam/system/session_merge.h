#pragma once
// Many drives, one map (`semslam merge`): the maps of several runs become the sessions of one atlas, which
// place recognition and GPS tie together into one map, written as a run folder.
//
//  1. Each run's map.semslam is appended to one atlas (map/map_file.h AppendMapFile): its sessions and maps
//     keep their own frames.
//  2. Maps a run placed in the world (its map file's geo section) are moved into one world frame: ENU around
//     the first such run's origin.
//  3. Place recognition across maps: every keyframe of a map is looked up among the other maps' keyframes,
//     as loop closing does it (loop/loop_closer.h), and a place found merges the two maps (Sim(3) for
//     monocular maps, SE(3) for stereo) with the essential-graph correction. Maps out of the world are tried
//     first and may merge into any map; a map in the world only merges into another one in the world, which
//     keeps the world frame. Then the drives of each merged map are looked up among each other's keyframes:
//     the streets they share beyond the merge's place close as loops (system/merge_places.h).
//  4. The final bundle adjustment of each map (windowed as the run's is: bounded in memory).
//  5. Maps in the world that no place tied together are joined by their GPS placement alone.
//  6. The map in the world is fused with every drive's GPS fixes (its run's log) in one pose graph with the
//     map's own links, and moved where that puts it: each merge took one map's place and the others followed
//     what vision saw.
//  7. The outputs of a run, for the whole atlas: map.semslam (the city map, loadable by `run --map-in`,
//     `localize` and the Python module), sessions/<id>-<name>/trajectory.tum (each drive's frames in the
//     merged map's frame, and trajectory_wgs84.csv in the world), semantic_map.ply, landmarks, topology,
//     objects, plots, report.html and run.json ("maps": {"sessions": [...]}).
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "semslam/system/run_metadata.h"

namespace semslam {

struct SessionMergeOptions {
  std::vector<std::filesystem::path>
      runs;  // run folders (map.semslam and run.json), or earlier merges' outputs
  std::filesystem::path output;
  bool overwrite = false;
  std::filesystem::path vocabulary;  // empty: the default vocabulary
  bool place_recognition = true;     // false: maps join through their GPS placement only
  bool loops_between_drives = true;  // loops between drives of a merged map (needs place_recognition)
  bool global_ba = true;             // the final bundle adjustment of each merged map
  bool gps_fusion = true;            // the merged map fused with every drive's GPS log (its run's --gps)
  int global_ba_iterations = 20;
  // The second pass's, to convergence: the merges and loops between drives bend each drive by the corrections
  // spread along it, which can leave the merged map further from its minimum than a run's own final BA
  // starts.
  int global_ba_refine_iterations = 100;
  int global_ba_window_keyframes = 1000;
  bool show_progress = true;
  RunProvenance provenance;
  void Check() const;  // throws InvalidArgument
};

struct SessionMergeSummary {
  size_t sessions = 0;
  size_t maps = 0;           // maps left in the atlas (1: every drive in one map)
  size_t place_merges = 0;   // maps merged by place recognition
  size_t session_loops = 0;  // loops closed between drives of one merged map
  size_t gps_joins = 0;      // maps joined by their GPS placement
  double seconds = 0.0;
};

// Throws InputError naming the file when a run folder lacks its map or run.json or holds a malformed one, and
// InvalidArgument when the runs' modes differ (monocular and stereo maps are not merged).
SessionMergeSummary MergeSessions(const SessionMergeOptions& options);

}  // namespace semslam
