#pragma once
// Place recognition between the maps and drives of a merge's atlas (system/session_merge.h, step 3).
#include <cstddef>
#include <cstdint>
#include <set>

namespace semslam {

class SlamSystem;

struct PlaceRecognitionSummary {
  size_t merges = 0;         // maps merged into others by a place they share
  size_t session_loops = 0;  // loops closed between two drives of one map
  int not_confirmed = 0;     // places the MergeVerifier refused or kept waiting
  bool interrupted = false;
};

// Every keyframe of a map is looked up among the other maps' keyframes, as loop closing does it
// (LoopCloser::ProcessKeyFrame), and a place found (and confirmed by a MergeVerifier) merges the two maps.
// Maps out of the world (not in `world_maps`) are tried first and may merge into any map; a map in the world
// merges only into another one in the world. Passes repeat until one merges nothing: a map merged late may
// hold the place another one needs. Then, in each merged map out of the world, every drive's keyframes are
// looked up among the other drives' keyframes of that map: a merge ties two drives at one place, and the
// streets they share beyond it are loops that hold them together along their length. A map in the world is
// left to the GPS fusion of all its drives (session_merge.h, step 6): there, such loops (each within the GPS
// check of a merge, monocular ones rescaling their neighbourhood by up to 7 %) put the four drives of a
// town 1.6-7.6 m off the truth where the fusion alone keeps them within 0.5 m. `world_maps` is kept current
// (a merged map in the world keeps its place there).
struct PlaceRecognitionOptions {
  bool loops_between_drives = true;
  bool show_progress = true;
};
PlaceRecognitionSummary RecognizePlacesAcrossDrives(SlamSystem& slam, std::set<std::uint32_t>& world_maps,
                                                    const PlaceRecognitionOptions& options);

}  // namespace semslam
