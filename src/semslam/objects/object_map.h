#pragma once
// The object-level map (paper §III-D): labeled map points clustered per class with DBSCAN (Ester et al. 1996)
// over a k-d tree (nanoflann) into objects with class, centroid, extent and point count.
//
// Units. Points are in the SLAM map frame. Cluster radii are given in metres and converted to map units by
// the map's scale: a georeference's, or else a monocular map's from the road beneath its camera
// (road_scale.h); a map with neither is taken to be metric. With a georeference objects get ENU and WGS84
// centroids too.

#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/geo/georeference.h"
#include "semslam/geometry/eigen_types.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

// A map point with its fused label (trainId; kNoLabel or anything out of range is ignored).
struct LabeledPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // map frame
  int label = kNoLabel;
  double confidence = 1.0;  // probability of the label, in [0, 1]
};

struct ClassClusterParams {
  bool enabled = true;
  double eps_m = 1.0;  // DBSCAN neighbourhood radius, metres
  int min_points = 5;  // neighbours (itself included) that make a point a core point
};

struct ObjectMapOptions {
  // Per trainId. Defaults: small radii for thin things (poles, signs, lights), about a car's gap for vehicles
  // and persons, larger ones for surfaces (road, sidewalk, terrain, building, vegetation); sky is disabled.
  std::array<ClassClusterParams, kNumClasses> per_class = DefaultParams();
  // Points whose label confidence is below this are left out.
  double min_confidence = 0.0;

  static std::array<ClassClusterParams, kNumClasses> DefaultParams();
  void Check() const;  // throws InvalidArgument
};

// An oriented box from the principal axes of the points: centre + rotation * (±half_extents).
struct OrientedBox {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // columns: principal axes, longest first
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
};

struct SemanticObject {
  int id = 0;
  int label = 0;  // trainId
  int num_points = 0;
  double mean_confidence = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // map frame
  Eigen::Vector3d box_min = Eigen::Vector3d::Zero();   // axis-aligned, map frame
  Eigen::Vector3d box_max = Eigen::Vector3d::Zero();
  OrientedBox pca_box;                          // map frame
  std::optional<Eigen::Vector3d> centroid_enu;  // with a georeference
  std::optional<Wgs84> centroid_wgs84;
  Eigen::Vector3d size_m = Eigen::Vector3d::Zero();  // PCA box edge lengths in metres, longest first
  std::vector<int> points;                           // indices into the input, ascending
};

struct ObjectMap {
  std::vector<SemanticObject> objects;              // by class, then in the order DBSCAN found them
  std::array<int, kNumClasses> clustered_points{};  // points of each class that were clustered
  std::array<int, kNumClasses> noise_points{};      // and those that were rejected as noise
  double metres_per_map_unit = 1.0;
  bool georeferenced = false;
  // Where metres_per_map_unit comes from: "georeference", "road" (the camera's height above the road) or
  // "map" (the map's unit taken as a metre: a stereo map's).
  std::string scale_source = "map";
};

// DBSCAN over the points of one class: the cluster id of each point (-1: noise). Deterministic: clusters are
// numbered in the order of their first core point; a border point reachable from two clusters joins the
// first.
std::vector<int> Dbscan(const Points3d& points, double eps, int min_points);

// Clusters every enabled class. `georeference` (optional) gives the scale and the ENU/WGS84 centroids;
// without one, `road_metres_per_map_unit` (optional, EstimateRoadScale) gives the scale.
ObjectMap BuildObjectMap(const std::vector<LabeledPoint>& points, const ObjectMapOptions& options = {},
                         const Georeference* georeference = nullptr,
                         std::optional<double> road_metres_per_map_unit = std::nullopt);

// objects.json (atomic): format, version, units, per-class parameters and counts, and every object with class
// name and trainId, centroid (map, ENU and WGS84 when georeferenced), axis-aligned box, PCA box, size in
// metres, point count and mean confidence.
void WriteObjectsJson(const std::filesystem::path& path, const ObjectMap& map,
                      const ObjectMapOptions& options);

}  // namespace semslam
