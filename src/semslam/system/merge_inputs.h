#pragma once
// What a merge (system/session_merge.h) reads of the run folders it is given, besides their maps: each run's
// sensor mode, landmark catalogues and the drives (sessions) whose frames it knows, with their GPS logs; and
// a drive's ground truth, for the merge's figures.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geo/wgs84.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/landmarks/catalogue.h"
#include "semslam/objects/road_scale.h"
#include "semslam/report/geo_evaluation.h"

namespace semslam {

// A session of an input whose frames are known (a run's own drive, or a drive an earlier merge wrote).
struct InputSession {
  std::string sequence;  // its sequence folder, for the ground truth
  std::string camera;
  std::filesystem::path frames_csv;  // each frame's map and pose in it, as the input's map holds them
  // The GPS log its run was given (empty: none), one fix every gps_every frames, and the antenna's place in
  // the camera frame when the run was told it.
  std::string gps;
  int gps_every = 30;
  std::optional<Eigen::Vector3d> lever_arm;
  // The camera's height above the road its run was given (`run --camera-height`; runs that did not record it
  // had the default).
  double camera_height_m = RoadScaleOptions{}.camera_height_m;
};

// One run folder given to merge: a run's (its own drive is its map file's last session) or a merge's.
struct InputRun {
  std::filesystem::path dir;
  std::string mode;  // "mono" or "stereo"
  std::vector<std::filesystem::path> catalogues;
  // By session index in the input's map file; a run's own session is its file's last (kLastSession).
  std::map<std::uint32_t, InputSession> sessions;
};
inline constexpr std::uint32_t kLastSession = UINT32_MAX;

// Throws InputError naming the file when `dir` holds no map or no run's run.json.
InputRun ReadInputRun(const std::filesystem::path& dir);

// Catalogues of all runs, each landmark once (same name within a metre).
std::vector<Landmark> UnionOfCatalogues(const std::vector<std::filesystem::path>& paths);

// A drive's ground truth, in its town's ENU frame when it has one (the synthetic city's scene.json: every
// drive of a town in one frame), else in its sequence's own frame.
struct SessionTruth {
  Trajectory world_from_camera;
  std::optional<EnuFrame> enu;                  // the frame of world_from_camera, when it is the town's ENU
  std::vector<SceneTruth::Landmark> landmarks;  // the town's, in that frame
};
// None (with a warning) when the drive has no ground truth or it cannot be read.
std::optional<SessionTruth> TruthOf(const InputSession& session, bool stereo);

}  // namespace semslam
