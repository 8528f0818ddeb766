#include "semslam/objects/road_scale.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <utility>

#include "semslam/core/error.h"

namespace semslam {

void RoadScaleOptions::Check() const {
  Require(std::isfinite(camera_height_m) && camera_height_m > 0,
          "road scale: camera_height_m must be a positive number of metres");
  Require(nearest_points >= 3 && min_inliers >= 3 && min_inliers <= nearest_points,
          "road scale: need 3 <= min_inliers <= nearest_points");
  Require(inlier_share > 0 && inlier_share < 1, "road scale: inlier_share must be in (0, 1)");
  Require(max_tilt_deg > 0 && max_tilt_deg < 90, "road scale: max_tilt_deg must be in (0, 90)");
  Require(min_keyframes >= 1 && ransac_iterations >= 1,
          "road scale: min_keyframes and ransac_iterations must be positive");
}

namespace {

struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitY();  // unit, pointing down (the camera's +y side)
  double offset = 0.0;  // normal . p = offset on the plane: the camera centre's distance from it
};

// The plane through three points, its normal turned down; empty when they are (nearly) on a line or the plane
// tilts more than `min_down` allows.
std::optional<Plane> PlaneThrough(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                  const Eigen::Vector3d& c, double min_down) {
  Eigen::Vector3d n = (b - a).cross(c - a);
  const double norm = n.norm();
  if (!(norm > 1e-12)) return std::nullopt;
  n /= norm;
  if (n.y() < 0) n = -n;
  if (n.y() < min_down) return std::nullopt;
  return Plane{n, n.dot(a)};
}

// Least squares through `points` (the normal: the covariance's least eigenvector).
std::optional<Plane> FitPlane(const std::vector<Eigen::Vector3d>& points, double min_down) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : points) covariance += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  Eigen::Vector3d n = solver.eigenvectors().col(0);
  if (n.y() < 0) n = -n;
  if (n.y() < min_down) return std::nullopt;
  return Plane{n, n.dot(centroid)};
}

// The camera's height above the road it sees, in map units, from the road points in its own frame.
std::optional<double> HeightAboveRoad(std::vector<Eigen::Vector3d> road, const RoadScaleOptions& options,
                                      std::uint32_t seed) {
  if (road.size() < static_cast<size_t>(options.min_inliers)) return std::nullopt;
  const size_t k = std::min(road.size(), static_cast<size_t>(options.nearest_points));
  std::nth_element(
      road.begin(), road.begin() + static_cast<std::ptrdiff_t>(k) - 1, road.end(),
      [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a.squaredNorm() < b.squaredNorm(); });
  road.resize(k);
  std::vector<double> below(k);
  for (size_t i = 0; i < k; ++i) below[i] = road[i].y();
  std::nth_element(below.begin(), below.begin() + static_cast<std::ptrdiff_t>(k / 2), below.end());
  const double threshold = options.inlier_share * below[k / 2];
  const double min_down = std::cos(options.max_tilt_deg * std::numbers::pi / 180.0);

  std::mt19937 random(seed);
  std::uniform_int_distribution<size_t> pick(0, k - 1);
  int best = 0;
  Plane best_plane;
  for (int iteration = 0; iteration < options.ransac_iterations; ++iteration) {
    const size_t i = pick(random), j = pick(random), l = pick(random);
    if (i == j || j == l || i == l) continue;
    const std::optional<Plane> plane = PlaneThrough(road[i], road[j], road[l], min_down);
    if (!plane) continue;
    int inliers = 0;
    for (const Eigen::Vector3d& p : road)
      inliers += std::abs(plane->normal.dot(p) - plane->offset) < threshold;
    if (inliers > best) {
      best = inliers;
      best_plane = *plane;
    }
  }
  if (best < options.min_inliers) return std::nullopt;
  std::vector<Eigen::Vector3d> inliers;
  for (const Eigen::Vector3d& p : road) {
    if (std::abs(best_plane.normal.dot(p) - best_plane.offset) < threshold) inliers.push_back(p);
  }
  const std::optional<Plane> refined = FitPlane(inliers, min_down);
  if (!refined || !(refined->offset > 0)) return std::nullopt;
  return refined->offset;
}

// The value at `share` (0..1) of sorted `values`, interpolated.
double Quantile(const std::vector<double>& sorted, double share) {
  const double at = share * static_cast<double>(sorted.size() - 1);
  const size_t below = static_cast<size_t>(std::floor(at));
  const size_t above = std::min(below + 1, sorted.size() - 1);
  return sorted[below] + (at - static_cast<double>(below)) * (sorted[above] - sorted[below]);
}

}  // namespace

std::optional<RoadScale> EstimateRoadScale(const std::vector<Rigid3d>& world_from_camera,
                                           const std::vector<LabeledPoint>& points,
                                           const RoadScaleOptions& options) {
  options.Check();
  constexpr int kRoad = TrainId(SemanticClass::kRoad);
  Points3d road;
  for (const LabeledPoint& p : points) {
    if (p.label == kRoad && p.position.allFinite()) road.push_back(p.position);
  }
  std::vector<double> heights;
  for (size_t index = 0; index < world_from_camera.size(); ++index) {
    const Rigid3d camera_from_world = world_from_camera[index].Inverse();
    std::vector<Eigen::Vector3d> below;  // road points ahead of and below the camera, in its frame
    for (const Eigen::Vector3d& p : road) {
      const Eigen::Vector3d in_camera = camera_from_world * p;
      if (in_camera.z() > 0 && in_camera.y() > 0) below.push_back(in_camera);
    }
    const std::optional<double> height =
        HeightAboveRoad(std::move(below), options, static_cast<std::uint32_t>(index));
    if (height) heights.push_back(*height);
  }
  if (heights.size() < static_cast<size_t>(options.min_keyframes)) return std::nullopt;
  std::sort(heights.begin(), heights.end());
  RoadScale scale;
  scale.keyframes = static_cast<int>(heights.size());
  scale.camera_height_map = Quantile(heights, 0.5);
  scale.spread = (Quantile(heights, 0.75) - Quantile(heights, 0.25)) / 2.0 / scale.camera_height_map;
  scale.metres_per_map_unit = options.camera_height_m / scale.camera_height_map;
  return scale;
}

}  // namespace semslam
