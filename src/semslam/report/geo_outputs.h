#pragma once
// Everything after SLAM that ties the map to the world, in one call for `semslam run`: GPS fusion (robust
// Sim(3) and the pose-graph fusion), the WGS84 trajectory, landmarks, the topological map, objects and plots.
// Plain data in, files out:
//
//   OUT/trajectory_wgs84.csv   t,lat,lon,alt for every tracked frame          (with GPS)
//   OUT/landmarks.geojson      WGS84 points with map_xyz, nearest keyframe, membership (with GPS and a
//   catalogue) OUT/topology.{geojson,graphml,dot,json}                                   (with GPS)
//   OUT/objects.json           clustered labeled points                       (with labeled points)
//   OUT/georeference.json      map -> ENU -> WGS84                            (with GPS)
//   OUT/plots/trajectory.png   the trajectory from above (against the ground truth when there is one)
//   OUT/plots/ate.png, rpe.png the errors along the drive                     (with a ground truth)
//   OUT/plots/gps.png, topology.png, membership.png                           (with GPS; landmarks)
//   OUT/plots/semantic_map.png                                                (with labeled points)
//
// and, for `semslam localize`, the map file's extra sections ("geo": georeference and placed landmarks;
// "topology": the topology JSON that `semslam route` reads).

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geo/gps.h"
#include "semslam/geo/gps_fusion.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/landmarks/catalogue.h"
#include "semslam/landmarks/landmark_map.h"
#include "semslam/objects/object_map.h"
#include "semslam/objects/road_scale.h"
#include "semslam/report/plots.h"
#include "semslam/topology/topological_map.h"

namespace semslam {

struct GeoInputs {
  std::vector<FramePose> frames;     // every tracked frame, in frame order (world_from_camera in the map)
  std::vector<FramePose> keyframes;  // in frame order, keyframe_id set
  std::vector<FusionEdge> edges;     // optional covisibility and loop edges (indices into keyframes)
  std::optional<GpsLog> gps;         // the GPS log, or
  std::filesystem::path gps_path;    // a KITTI oxts folder, CSV or NMEA file (read when `gps` is empty)
  std::optional<std::vector<Landmark>> landmarks;  // the catalogue as read (OSM not yet limited), or
  std::filesystem::path landmarks_path;  // CSV, GeoJSON or OSM catalogue (read when `landmarks` is empty)
  std::vector<LabeledPoint> points;      // labeled map points (map frame)
  bool monocular = true;                 // Sim(3) alignment and fusion; false: SE(3) (stereo)
  std::optional<Trajectory> truth;       // the sequence's ground truth (world_from_camera, metres), for plots
  std::optional<Wgs84> enu_origin;       // default: the first GPS fix
  // The map of `frames` and `keyframes` already placed in the world by its GPS (system/atlas_georeference.h):
  // no GPS is read or fused here, and `placed` gives the georeference and what the GPS plot shows.
  struct Placed {
    Georeference georeference;
    std::vector<GpsSample> samples;
    std::vector<bool> inliers;
    Points3d single_similarity_enu;  // per frame of `frames`: where one similarity put it (the paper's fit)
    double fit_rmse_m = 0.0;
    double single_similarity_rmse_m = 0.0;
    std::string gps_format;
    int gps_fixes = 0, gps_skipped = 0;
    double time_offset_s = 0.0;
  };
  std::optional<Placed> placed;
  std::uint32_t map_id = 0;  // the atlas map of `frames` and `keyframes`
  // The atlas's other maps in the world, for the map file's geo section (map id -> georeference).
  std::map<std::uint32_t, Georeference> other_maps;
};

struct GeoOptions {
  GpsReadOptions gps_read;
  GpsFusionOptions fusion;  // sampling (every 30 frames), robust alignment, pose graph; estimate_scale is set
                            // from GeoInputs::monocular
  bool fuse = true;         // the pose-graph fusion; false: the single robust similarity (the paper's method)
  std::optional<double> time_offset_s;  // frame time + offset = GPS time; default: GuessTimeOffset
  LandmarkOptions landmarks;
  double osm_radius_m = 150.0;  // OSM catalogues: features within this distance of the trajectory
  TopologyOptions topology;
  ObjectMapOptions objects;
  // A monocular map without a georeference: its objects' scale from the camera's height above the road; none:
  // its objects stay in map units (a merge of drives whose cameras rode at different heights).
  std::optional<RoadScaleOptions> road_scale = RoadScaleOptions{};
  bool write_plots = true;
  PlotOptions plots;
  double raster_cell_m = 2.0;

  void Check() const;  // throws InvalidArgument
};

// Figures for run.json.
struct GeoSummary {
  bool georeferenced = false;
  bool fused = false;
  std::string gps_format;
  int gps_fixes = 0, gps_skipped = 0, gps_samples = 0, gps_inliers = 0;
  double time_offset_s = 0.0;
  double metres_per_map_unit = 1.0;
  double single_sim3_rmse_m = 0.0;  // residuals of the robust similarity, inliers
  double fused_rmse_m = 0.0;        // residuals after the fusion, inliers
  int landmarks = 0, landmarks_associated = 0;
  int topology_nodes = 0, topology_landmark_nodes = 0, topology_turn_nodes = 0, topology_edges = 0,
      topology_revisited_nodes = 0;
  int objects = 0;
  std::map<std::string, int> objects_per_class;
  // The objects' metres per map unit and its source (ObjectMap::scale_source); for "road", the keyframes that
  // fitted the road beneath them and the spread of their heights (RoadScale).
  double objects_metres_per_map_unit = 1.0;
  std::string objects_scale_source = "map";
  int road_scale_keyframes = 0;
  double road_scale_spread = 0.0;
  int trajectory_frames = 0;

  std::string ToJson() const;  // one JSON object
};

struct GeoOutputs {
  std::optional<Georeference> georeference;
  std::vector<GpsSample> samples;         // (GPS, frame) pairs sampled every N frames
  std::optional<GpsAlignment> alignment;  // the robust similarity of the samples
  std::optional<GpsFusionResult> fusion;  // when fused
  std::vector<PlacedLandmark> landmarks;
  std::optional<TopologicalMap> topology;
  ObjectMap objects;
  std::map<std::string, std::string> map_sections;  // for MapFileContents::extra_sections
  std::vector<std::filesystem::path> files;         // written
  GeoSummary summary;
};

// Throws InputError for unreadable GPS logs or catalogues, InvalidArgument for bad options or inputs. Missing
// GPS is not an error: only objects (a monocular map's scale from the road beneath its camera, else its
// metric radii taken as map units) and the semantic map plot are written.
GeoOutputs WriteGeoOutputs(const GeoInputs& inputs, const std::filesystem::path& out_dir,
                           const GeoOptions& options = {});

// ---- For `semslam localize` ----

// What the map file's "geo" section holds: the georeference of each map of the atlas in the world, and the
// landmarks, placed in one of them.
struct GeoContext {
  std::map<std::uint32_t, Georeference> maps;  // by map id; a map not named is not in the world
  std::vector<PlacedLandmark> landmarks;
  std::uint32_t landmarks_map = 0;  // the map the landmarks were placed in
  double sigma_m = 25.0;

  const Georeference* Of(std::uint32_t map_id) const {
    const auto it = maps.find(map_id);
    return it == maps.end() ? nullptr : &it->second;
  }
};
std::string GeoSectionJson(const GeoContext& context);
// Throws InputError naming `source` (e.g. "map.semslam#geo") and the field. A version-1 section (one map: the
// whole file's) is read as the georeference of map `single_map_id`.
GeoContext ParseGeoSection(const std::string& text, const std::filesystem::path& source,
                           std::uint32_t single_map_id);

struct NamedMembership {
  std::string name;
  double distance_m = 0.0;  // horizontal
  Membership membership;
};
struct GeoPose {
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();
  Wgs84 wgs84;
  double heading_deg = 0.0;  // compass bearing of the camera's viewing direction (0 north, 90 east)
  std::vector<NamedMembership> nearest;  // nearest landmarks first
};
// A pose of a map in the world (`georeference`: its own); the nearest landmarks only when they were placed in
// that map.
GeoPose LocateInWorld(const Rigid3d& world_from_camera, const Georeference& georeference,
                      const GeoContext& context, bool with_landmarks, size_t max_landmarks = 3);

}  // namespace semslam
