#pragma once
// Landmark-level relocalization without GPS (`semslam localize`): every frame of a sequence is localized
// against a saved map (relocalization by bag of words and PnP, then tracking against the map, which is never
// changed), and reported in the map, in WGS84 and as the landmarks it is near, with their fuzzy memberships,
// through the georeference and landmarks the map file carries.
//
// Every map of the file is searched. A pose is in the world only when the map it is in has a georeference
// (the map file's, or one this session's GPS gives it): a map that is not in the world yields no WGS84
// position and no landmarks.
//
// Writes into the output folder: trajectory.tum (map frame, localized frames), localization.csv (one line per
// frame: status, map, pose in that map, WGS84, heading and the nearest landmarks) and localize.json (summary,
// the frames per map and whether each is in the world, and, for a synthetic-city sequence, the errors against
// its truth).

#include <cstddef>
#include <filesystem>
#include <limits>
#include <string>

#include "semslam/system/slam_system.h"

namespace semslam {

struct LocalizeOptions {
  std::filesystem::path map;       // map.semslam of an earlier `semslam run`
  std::filesystem::path sequence;  // any sequence OpenSequence reads
  std::string camera;  // of a KITTI folder (io/sequence.h SequenceOptions::camera); empty: default
  std::filesystem::path output;
  SlamOptions slam;  // mode, features, vocabulary; localization_only is forced
  size_t first_frame = 0;
  size_t end_frame = std::numeric_limits<size_t>::max();
  size_t max_landmarks = 3;  // nearest landmarks reported per frame
  // A GPS log of the session (optional): a map the map file does not place in the world is placed by the
  // robust similarity of the frames localized in it onto their fixes, one every `gps_every` frames.
  std::filesystem::path gps;
  int gps_every = 30;
  bool show_progress = true;
  bool overwrite = false;             // as RunOptions::overwrite (system/run_output_dir.h)
  size_t max_bad_frames_in_row = 10;  // as RunOptions::max_bad_frames_in_row

  void Check() const;
};

struct LocalizeSummary {
  size_t frames = 0;
  size_t localized = 0;  // frames with a pose
  size_t in_world = 0;   // of them, in a map with a georeference (they have a WGS84 position)
  size_t relocalizations = 0;
  double seconds = 0.0;
  // Against the truth of a synthetic-city sequence (negative when unknown): the share of all frames localized
  // within 1 m (ENU through the map's georeference when it has one, else after a similarity alignment), and
  // the share of localized frames whose nearest landmark is the truly nearest one.
  double within_1m = -1.0;
  double nearest_landmark_right = -1.0;
};

// Throws InputError for unreadable inputs, InvalidArgument for bad options.
LocalizeSummary LocalizeSequence(const LocalizeOptions& options);

}  // namespace semslam
