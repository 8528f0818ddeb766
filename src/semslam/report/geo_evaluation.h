#pragma once
// Geo outputs against the synthetic city's ground truth (scene.json and poses/<seq>.txt), for run.json and
// the bars: landmark position error and the WGS84 trajectory's absolute error.
//
// Landmark position error. A landmark is placed in the map at map_xyz; where that point truly is follows from
// the map around it: its nearest keyframe's true pose and the map's local scale there (true over estimated
// path length within `scale_window_m` of the keyframe). The error is the distance between that true place and
// the landmark's true position (3D and horizontal).
//
// Trajectory error. Each tracked frame's WGS84 position (as in trajectory_wgs84.csv) against the true camera
// centre, in metres, without any alignment.

#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "semslam/geo/wgs84.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/geometry/sim3.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/report/geo_outputs.h"

namespace semslam {

struct SceneTruth {
  Wgs84 origin;                            // of the scene's ENU frame
  Rigid3d enu_from_world;                  // world = the first camera's frame
  Points3d positions_world;                // true camera centres, per frame
  std::vector<Rigid3d> world_from_camera;  // true poses per frame (poses/<seq>.txt); may be empty
  struct Landmark {
    std::string name;
    std::string category;
    Eigen::Vector3d enu = Eigen::Vector3d::Zero();
    int nearest_frame = 0;
  };
  std::vector<Landmark> landmarks;
  struct Turn {
    int frame = 0;
    Eigen::Vector3d world = Eigen::Vector3d::Zero();
    bool left = true;
    int intersection = -1;
  };
  std::vector<Turn> turns;
  struct Revisit {
    int frame = 0, earlier_frame = 0;
  };
  std::vector<Revisit> revisits;
  struct Intersection {
    int id = 0;
    Eigen::Vector3d enu = Eigen::Vector3d::Zero();
    bool drivable = true;
  };
  std::vector<Intersection> intersections;
  struct Segment {
    int id = 0, from = 0, to = 0;
    double length = 0.0;
    int driven = 0;  // times driven within the frames
  };
  std::vector<Segment> segments;

  Eigen::Vector3d TrueEnu(size_t frame) const { return enu_from_world * positions_world.at(frame); }
};

// DIR/scene.json, and DIR/poses/<sequence>.txt when present. Throws InputError naming the file and field.
SceneTruth ReadSceneTruth(const std::filesystem::path& dataset_dir, const std::string& sequence = "00");

struct GeoEvaluation {
  int trajectory_frames = 0;
  double trajectory_ate_rmse_m = 0.0, trajectory_ate_max_m = 0.0;
  int landmarks = 0;  // placed landmarks found in the truth by name, with a nearest keyframe within reach
  int landmarks_too_far = 0;
  double landmark_error_median_m = 0.0, landmark_error_max_m = 0.0;  // 3D
  double landmark_error_horizontal_median_m = 0.0, landmark_error_horizontal_max_m = 0.0;
  struct LandmarkError {
    std::string name;
    double error_m = 0.0, horizontal_m = 0.0;
  };
  std::vector<LandmarkError> landmark_errors;

  std::string ToJson() const;
};

struct GeoEvaluationOptions {
  double scale_window_m = 50.0;
  // Landmarks farther than this from their nearest keyframe are not evaluated (counted in
  // landmarks_too_far): the map says little about places far from where it was driven.
  double max_distance_m = 100.0;
  void Check() const;
};

// Needs the georeference (GPS) in `outputs`; frames beyond the truth are skipped. Landmark errors need the
// true poses (SceneTruth::world_from_camera).
GeoEvaluation EvaluateGeo(const GeoOutputs& outputs, const GeoInputs& inputs, const SceneTruth& truth,
                          const GeoEvaluationOptions& options = {});

// The landmarks of a map merged from several drives of one town (`semslam merge`), measured as above through
// their nearest keyframe's true pose, which may be any drive's: `keyframes` carry the drive in their
// `segment`, `truths` each drive's true poses in the town's ENU frame (by segment, in time order), and
// `town_from_map` takes the merged map (metric, in the world) into that frame. Fills the landmark fields;
// landmarks whose keyframe has no true pose are left out.
GeoEvaluation EvaluateLandmarksAcrossDrives(const std::vector<PlacedLandmark>& placed,
                                            const std::vector<FramePose>& keyframes,
                                            const std::map<std::uint32_t, Trajectory>& truths,
                                            const Sim3d& town_from_map,
                                            const std::vector<SceneTruth::Landmark>& truth_landmarks);

}  // namespace semslam
