#pragma once
// Runs the whole pipeline over an image sequence and writes every output into a directory:
// trajectory.tum, keyframes.tum, trajectory.kitti, map.semslam, timing.json, run.json (and, as the
// semantic and geographic parts are enabled, their outputs too).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "semslam/geometry/eigen_types.h"
#include "semslam/objects/road_scale.h"
#include "semslam/system/run_metadata.h"
#include "semslam/system/slam_system.h"

namespace semslam {

struct RunOptions {
  std::filesystem::path sequence;
  std::string camera;  // of a KITTI folder (io/sequence.h SequenceOptions::camera); empty: its default
  std::filesystem::path output;
  SlamOptions slam;
  size_t first_frame = 0;
  size_t end_frame = std::numeric_limits<size_t>::max();  // exclusive
  std::filesystem::path map_in;                           // start from this map (relocalize first)
  // Semantic segmentation of keyframes (semantics/segmenter.h MakeSegmenter spec: none, enet:FILE,
  // onnx:CARD.yaml, labels:DIR, truth-noisy:RATE, ...).
  std::string segmenter = "none";
  std::uint64_t seed = 0;  // for noisy segmenters
  // Ties the map to the world: a GPS log (KITTI oxts folder, CSV t,lat,lon[,alt,sigma] or NMEA) and a
  // landmark catalogue (CSV, GeoJSON or OpenStreetMap); empty: none.
  std::filesystem::path gps;
  std::filesystem::path landmarks;
  bool gps_fusion =
      true;            // pose-graph fusion of the fixes; false: one robust similarity (the paper's method)
  int gps_every = 30;  // frames between the GPS fixes used (one sample per N frames)
  // Where the GPS antenna is in the camera frame (metres); default: the sequence's calibration says (a KITTI
  // raw drive's OXTS unit), else at the camera.
  std::optional<Eigen::Vector3d> gps_antenna_in_camera_m;
  // The camera's height above the road (metres): a monocular map without GPS takes its objects' scale from it
  // (objects/road_scale.h).
  double camera_height_m = RoadScaleOptions{}.camera_height_m;
  bool save_map = true;
  bool show_progress = true;
  RunProvenance provenance;  // the command line and the binary's version, for run.json
  // An --out that holds an earlier run is refused unless this is set; then it is emptied first
  // (system/run_output_dir.h).
  bool overwrite = false;
  // Bad frames (unreadable, truncated, of another size) are skipped; more than this many in a row stop the
  // run, which then saves what it did.
  size_t max_bad_frames_in_row = 10;

  void Check() const;
};

struct RunSummary {
  SlamStatistics statistics;
  double seconds = 0.0;
  double ate_rmse = -1.0;  // against the sequence's ground truth, when it has one (Sim(3) mono, SE(3) stereo)
  double label_accuracy = -1.0;  // map-point labels against the synthetic city's surfaces, when known
  // "complete", "interrupted" (a signal; RunSequence then throws Interrupted after saving) or
  // "stopped_bad_frames" (it then throws InputError after saving).
  std::string status = "complete";
  size_t bad_frames = 0;
};

// Throws InputError for unreadable inputs and InvalidArgument for bad options. A run stopped by a signal
// (core/interrupt.h) saves the trajectory of the frames done, the map and run.json (status "interrupted"),
// then throws Interrupted; one stopped by too many bad frames in a row saves the same, then throws
// InputError.
RunSummary RunSequence(const RunOptions& options);

// Parses "A:B" (either side may be empty) into [first, end). Throws InvalidArgument.
void ParseFrameRange(const std::string& text, size_t* first, size_t* end);

class ImageSequence;
// The end of the frames [first, end) that `command` runs over, clamped to the sequence. Throws
// InvalidArgument when no frame is left, InputError when stereo is asked of a sequence without a second
// camera.
size_t CheckFrameRange(const ImageSequence& sequence, size_t first, size_t end, bool stereo,
                       std::string_view command);

}  // namespace semslam
