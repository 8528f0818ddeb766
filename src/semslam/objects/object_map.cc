#include "semslam/objects/object_map.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <nanoflann.hpp>

#include "semslam/core/error.h"

namespace semslam {

namespace {

// nanoflann's dataset adaptor over a point vector.
struct PointCloud {
  const Points3d& points;
  size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(size_t index, size_t dim) const {
    return points[index][static_cast<Eigen::Index>(dim)];
  }
  template <class BBox>
  bool kdtree_get_bbox(BBox& /*bb*/) const {
    return false;
  }
};

using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointCloud>,
                                                   PointCloud, 3, size_t>;

OrientedBox PcaBox(const Points3d& points, const Eigen::Vector3d& centroid) {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) covariance += (p - centroid) * (p - centroid).transpose();
  covariance /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  // Eigenvalues ascending: reverse to longest first; keep a right-handed frame.
  Eigen::Matrix3d axes;
  axes.col(0) = solver.eigenvectors().col(2);
  axes.col(1) = solver.eigenvectors().col(1);
  axes.col(2) = axes.col(0).cross(axes.col(1));
  Eigen::Vector3d low = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d high = -low;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d local = axes.transpose() * (p - centroid);
    low = low.cwiseMin(local);
    high = high.cwiseMax(local);
  }
  OrientedBox box;
  box.rotation = Eigen::Quaterniond(axes).normalized();
  box.center = centroid + axes * (0.5 * (low + high));
  box.half_extents = 0.5 * (high - low);
  return box;
}

}  // namespace

std::array<ClassClusterParams, kNumClasses> ObjectMapOptions::DefaultParams() {
  std::array<ClassClusterParams, kNumClasses> p{};
  const auto set = [&](SemanticClass c, double eps_m, int min_points) {
    p[static_cast<size_t>(TrainId(c))] = ClassClusterParams{true, eps_m, min_points};
  };
  set(SemanticClass::kRoad, 2.0, 20);
  set(SemanticClass::kSidewalk, 1.5, 15);
  set(SemanticClass::kBuilding, 1.5, 15);
  set(SemanticClass::kWall, 1.0, 10);
  set(SemanticClass::kFence, 1.0, 10);
  set(SemanticClass::kPole, 0.5, 5);
  set(SemanticClass::kTrafficLight, 0.5, 4);
  set(SemanticClass::kTrafficSign, 0.5, 4);
  set(SemanticClass::kVegetation, 1.5, 10);
  set(SemanticClass::kTerrain, 2.0, 15);
  set(SemanticClass::kSky, 5.0, 10);
  p[static_cast<size_t>(TrainId(SemanticClass::kSky))].enabled = false;  // sky points are far and meaningless
  set(SemanticClass::kPerson, 0.7, 5);
  set(SemanticClass::kRider, 0.7, 5);
  set(SemanticClass::kCar, 1.0, 8);
  set(SemanticClass::kTruck, 1.5, 8);
  set(SemanticClass::kBus, 1.5, 8);
  set(SemanticClass::kTrain, 2.0, 8);
  set(SemanticClass::kMotorcycle, 0.7, 5);
  set(SemanticClass::kBicycle, 0.7, 5);
  return p;
}

void ObjectMapOptions::Check() const {
  for (int c = 0; c < kNumClasses; ++c) {
    const ClassClusterParams& p = per_class[static_cast<size_t>(c)];
    if (!p.enabled) continue;
    Require(std::isfinite(p.eps_m) && p.eps_m > 0,
            "objects: eps_m of class '" + std::string(ClassName(c)) + "' must be positive");
    Require(p.min_points >= 1,
            "objects: min_points of class '" + std::string(ClassName(c)) + "' must be >= 1");
  }
  Require(min_confidence >= 0 && min_confidence <= 1, "objects: min_confidence must be in [0, 1]");
}

std::vector<int> Dbscan(const Points3d& points, double eps, int min_points) {
  Require(std::isfinite(eps) && eps > 0, "DBSCAN eps must be positive");
  Require(min_points >= 1, "DBSCAN min_points must be >= 1");
  constexpr int kUnvisited = -2, kNoise = -1;
  std::vector<int> cluster(points.size(), kUnvisited);
  if (points.empty()) return {};
  for (const Eigen::Vector3d& p : points) Require(p.allFinite(), "DBSCAN: point is not finite");
  const PointCloud cloud{points};
  KdTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const double radius_sq = eps * eps;  // L2_Simple works on squared distances
  nanoflann::SearchParams params;
  params.sorted = false;
  std::vector<std::pair<size_t, double>> neighbours;
  const auto region = [&](size_t i) {
    neighbours.clear();
    tree.radiusSearch(points[i].data(), radius_sq, neighbours, params);
    // Ascending indices: the order in which border points are claimed does not depend on the tree.
    std::sort(neighbours.begin(), neighbours.end());
  };

  int next_cluster = 0;
  std::vector<size_t> queue;
  for (size_t i = 0; i < points.size(); ++i) {
    if (cluster[i] != kUnvisited) continue;
    region(i);
    if (static_cast<int>(neighbours.size()) < min_points) {
      cluster[i] = kNoise;  // may still become a border point of a later cluster
      continue;
    }
    const int id = next_cluster++;
    cluster[i] = id;
    queue.clear();
    for (const auto& [j, d] : neighbours) {
      if (cluster[j] == kUnvisited || cluster[j] == kNoise) {
        if (cluster[j] == kUnvisited) queue.push_back(j);
        cluster[j] = id;
      }
    }
    for (size_t q = 0; q < queue.size(); ++q) {
      const size_t j = queue[q];
      region(j);
      if (static_cast<int>(neighbours.size()) < min_points) continue;  // border point
      for (const auto& [k, d] : neighbours) {
        if (cluster[k] == kUnvisited) {
          queue.push_back(k);
          cluster[k] = id;
        } else if (cluster[k] == kNoise) {
          cluster[k] = id;
        }
      }
    }
  }
  return cluster;
}

ObjectMap BuildObjectMap(const std::vector<LabeledPoint>& points, const ObjectMapOptions& options,
                         const Georeference* georeference, std::optional<double> road_metres_per_map_unit) {
  options.Check();
  ObjectMap map;
  map.georeferenced = georeference != nullptr;
  if (georeference) {
    map.metres_per_map_unit = georeference->MetresPerMapUnit();
    map.scale_source = "georeference";
  } else if (road_metres_per_map_unit) {
    map.metres_per_map_unit = *road_metres_per_map_unit;
    map.scale_source = "road";
  }
  Require(std::isfinite(map.metres_per_map_unit) && map.metres_per_map_unit > 0,
          "objects: the map's scale (" + map.scale_source + ") must be positive");

  std::array<std::vector<int>, kNumClasses> members;
  for (size_t i = 0; i < points.size(); ++i) {
    const LabeledPoint& p = points[i];
    if (!IsValidTrainId(p.label) || !options.per_class[static_cast<size_t>(p.label)].enabled) continue;
    if (!(p.confidence >= options.min_confidence) || !p.position.allFinite()) continue;
    members[static_cast<size_t>(p.label)].push_back(static_cast<int>(i));
  }

  for (int c = 0; c < kNumClasses; ++c) {
    const std::vector<int>& indices = members[static_cast<size_t>(c)];
    if (indices.empty()) continue;
    const ClassClusterParams& params = options.per_class[static_cast<size_t>(c)];
    Points3d positions;
    positions.reserve(indices.size());
    for (const int i : indices) positions.push_back(points[static_cast<size_t>(i)].position);
    const std::vector<int> cluster =
        Dbscan(positions, params.eps_m / map.metres_per_map_unit, params.min_points);
    const int num_clusters = cluster.empty() ? 0 : *std::max_element(cluster.begin(), cluster.end()) + 1;
    std::vector<std::vector<int>> groups(static_cast<size_t>(std::max(num_clusters, 0)));
    for (size_t k = 0; k < cluster.size(); ++k) {
      if (cluster[k] < 0) {
        ++map.noise_points[static_cast<size_t>(c)];
        continue;
      }
      ++map.clustered_points[static_cast<size_t>(c)];
      groups[static_cast<size_t>(cluster[k])].push_back(static_cast<int>(k));
    }
    for (const std::vector<int>& group : groups) {
      SemanticObject object;
      object.id = static_cast<int>(map.objects.size());
      object.label = c;
      object.num_points = static_cast<int>(group.size());
      Points3d cluster_points;
      cluster_points.reserve(group.size());
      double confidence = 0.0;
      for (const int k : group) {
        const int i = indices[static_cast<size_t>(k)];
        object.points.push_back(i);
        cluster_points.push_back(points[static_cast<size_t>(i)].position);
        confidence += points[static_cast<size_t>(i)].confidence;
      }
      std::sort(object.points.begin(), object.points.end());
      object.mean_confidence = confidence / static_cast<double>(group.size());
      object.centroid = Eigen::Vector3d::Zero();
      object.box_min = cluster_points.front();
      object.box_max = cluster_points.front();
      for (const Eigen::Vector3d& p : cluster_points) {
        object.centroid += p;
        object.box_min = object.box_min.cwiseMin(p);
        object.box_max = object.box_max.cwiseMax(p);
      }
      object.centroid /= static_cast<double>(cluster_points.size());
      object.pca_box = PcaBox(cluster_points, object.centroid);
      object.size_m = 2.0 * object.pca_box.half_extents * map.metres_per_map_unit;
      if (georeference) {
        object.centroid_enu = georeference->MapToEnu(object.centroid);
        object.centroid_wgs84 = georeference->enu_frame.ToWgs84(*object.centroid_enu);
      }
      map.objects.push_back(std::move(object));
    }
  }
  return map;
}

}  // namespace semslam
