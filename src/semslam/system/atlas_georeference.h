#pragma once
// GPS across the atlas (paper §III-C, beyond it): every map of a run with enough fixes on its frames is fused
// with them (geo/gps_fusion.h: a pose graph with the fixes as robust priors) and moved into the world, ENU
// metres around one origin (mapping/map_georeference.h), so that a drive is in the world from end to end
// whether or not its maps merged visually. Maps in the world share one frame, and are then joined into one
// map (the largest of them): the GPS is the thread between maps that no place tied together.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geo/georeference.h"
#include "semslam/geo/gps.h"
#include "semslam/geo/gps_fusion.h"

namespace semslam {

class SlamSystem;

struct AtlasGeoreferenceOptions {
  // Sampling (one fix every N frames), the robust similarity (estimate_scale: set for monocular maps by the
  // caller), the pose graph and the antenna's place beside the camera.
  GpsFusionOptions fusion;
  bool fuse = true;  // the pose graph; false: one robust similarity per map (the paper's method)
  bool join = true;  // maps placed in the world are joined into one
  std::optional<double> time_offset_s;  // frame time + offset = GPS time; default: GuessTimeOffset

  void Check() const;  // throws InvalidArgument
};

// One map of the atlas, as its GPS placed it.
struct MapGeoreferenceSummary {
  std::uint32_t map_id = 0;
  size_t frames = 0;                      // this run's frames with a pose in it, before any joining
  size_t keyframes = 0;                   // its keyframes
  int samples = 0;                        // fixes sampled on its frames
  int inliers = 0;                        // of them, those the fusion kept
  double fit_rmse_m = 0.0;                // the kept fixes against the fused antenna positions
  double single_similarity_rmse_m = 0.0;  // the kept fixes against the one similarity (the paper's fit)
  bool in_world = false;
  bool roll_from_cameras = false;            // on (or near) one line: the cameras' down axis set the roll
  std::string reason;                        // why not, when not
  std::optional<std::uint32_t> joined_into;  // the map it was joined into, when joined
  // For the GPS plot: the samples (fixes in ENU), which the fusion kept, and this run's frames of the map
  // placed by the one similarity (frame index, ENU position), as they were before the map moved.
  std::vector<GpsSample> gps_samples;
  std::vector<bool> gps_inliers;
  std::vector<std::pair<size_t, Eigen::Vector3d>> single_similarity_frames;
};

struct AtlasGeoreference {
  std::optional<EnuFrame> enu;  // the world frame: ENU around the GPS log's first fix, or a known map's
  double time_offset_s = 0.0;   // frame time + offset = GPS time
  std::vector<MapGeoreferenceSummary> maps;
  // The maps in the world after joining (map ids); the first is the one holding most of this run's frames.
  std::vector<std::uint32_t> world_maps;
};

// Fuses and moves every map of `slam` (after Finish) that has at least `fusion.alignment.min_samples` fixes
// on its frames. `known` gives the maps placed in the world before (loaded with a georeference): they are
// fused from where it puts them, and the ENU frame of the first is the run's world frame (else ENU around the
// log's first fix). Maps whose fixes do not determine their place stay where they are, out of the world.
// Throws InvalidArgument on bad options.
AtlasGeoreference GeoreferenceAtlas(SlamSystem& slam, const GpsLog& log,
                                    const std::map<std::uint32_t, Georeference>& known,
                                    const AtlasGeoreferenceOptions& options);

}  // namespace semslam
