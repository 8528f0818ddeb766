#include "semslam/objects/road_scale.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "semslam/core/error.h"

namespace semslam {
namespace {

constexpr int kRoad = TrainId(SemanticClass::kRoad);
constexpr int kCar = TrainId(SemanticClass::kCar);
constexpr double kCameraHeight = 1.65;

// A camera at kCameraHeight above the road plane z = 0 (z up), heading `heading` radians from +x, with its
// own axes x right, y down, z forward.
Rigid3d CameraOnRoad(const Eigen::Vector2d& at, double heading) {
  const Eigen::Vector3d forward(std::cos(heading), std::sin(heading), 0.0);
  const Eigen::Vector3d right(std::sin(heading), -std::cos(heading), 0.0);
  Eigen::Matrix3d rotation;
  rotation << right, Eigen::Vector3d(0, 0, -1), forward;
  return Rigid3d(rotation, Eigen::Vector3d(at.x(), at.y(), kCameraHeight));
}

struct Drive {
  std::vector<Rigid3d> world_from_camera;
  std::vector<LabeledPoint> points;
};

// A drive along a curve, its road points 2-20 m ahead (2 cm noise), mislabelled "road" points on facades and
// cars, and cars; everything then divided by `metres_per_map_unit`, as a monocular map would hold it.
Drive CurvedDrive(double metres_per_map_unit, double mislabelled_share) {
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 0.02);
  std::uniform_real_distribution<double> ahead(2.0, 20.0), across(-4.0, 4.0), unit(0.0, 1.0);
  Drive drive;
  for (int k = 0; k < 40; ++k) {
    const double s = 2.0 * k, heading = 0.01 * s;
    const Eigen::Vector2d at(s * std::cos(0.005 * s), s * std::sin(0.005 * s));
    const Rigid3d camera = CameraOnRoad(at, heading);
    drive.world_from_camera.push_back(camera);
    const Eigen::Vector3d forward = camera.rotation * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d right = camera.rotation * Eigen::Vector3d::UnitX();
    for (int i = 0; i < 30; ++i) {
      Eigen::Vector3d p =
          Eigen::Vector3d(at.x(), at.y(), 0.0) + ahead(random) * forward + across(random) * right;
      p.z() += noise(random);
      int label = kRoad;
      if (unit(random) < mislabelled_share) p.z() = 3.0 * unit(random);  // a facade or a car read as road
      if (unit(random) < 0.2) label = kCar;
      drive.points.push_back({p, label, 0.9});
    }
  }
  for (Rigid3d& pose : drive.world_from_camera) pose.translation /= metres_per_map_unit;
  for (LabeledPoint& p : drive.points) p.position /= metres_per_map_unit;
  return drive;
}

TEST(RoadScale, MonocularUnitsFromTheCameraHeight) {
  constexpr double kMetresPerMapUnit = 7.3;
  const Drive drive = CurvedDrive(kMetresPerMapUnit, 0.2);
  const std::optional<RoadScale> scale = EstimateRoadScale(drive.world_from_camera, drive.points);
  ASSERT_TRUE(scale.has_value());
  EXPECT_EQ(scale->keyframes, 40);
  // Measured 0.03 % off (spread 0.26 %): the road points' 2 cm noise; a fifth of them off the road do not
  // pull it.
  EXPECT_NEAR(scale->metres_per_map_unit, kMetresPerMapUnit, 0.002 * kMetresPerMapUnit);
  EXPECT_NEAR(scale->camera_height_map * kMetresPerMapUnit, kCameraHeight, 0.002 * kCameraHeight);
  EXPECT_LT(scale->spread, 0.005);
}

TEST(RoadScale, TheCameraHeightGivenSetsTheScale) {
  const Drive drive = CurvedDrive(1.0, 0.0);
  RoadScaleOptions options;
  options.camera_height_m = 2.0 * kCameraHeight;  // a truck's camera: the same map is twice as large
  const std::optional<RoadScale> scale = EstimateRoadScale(drive.world_from_camera, drive.points, options);
  ASSERT_TRUE(scale.has_value());
  EXPECT_NEAR(scale->metres_per_map_unit, 2.0, 0.01);
}

TEST(RoadScale, NoScaleWithoutEnoughRoadBeneathTheCameras) {
  Drive drive = CurvedDrive(1.0, 0.0);
  for (LabeledPoint& p : drive.points) {
    if (p.label == kRoad) p.label = kCar;
  }
  EXPECT_FALSE(EstimateRoadScale(drive.world_from_camera, drive.points).has_value());
  // Road only above the cameras (a ceiling): nothing beneath them.
  drive = CurvedDrive(1.0, 0.0);
  for (LabeledPoint& p : drive.points) p.position.z() += 10.0;
  EXPECT_FALSE(EstimateRoadScale(drive.world_from_camera, drive.points).has_value());
  drive = CurvedDrive(1.0, 0.0);
  drive.world_from_camera.resize(4);  // fewer keyframes than min_keyframes
  EXPECT_FALSE(EstimateRoadScale(drive.world_from_camera, drive.points).has_value());
}

TEST(RoadScale, ObjectsTakeTheRoadScale) {
  std::vector<LabeledPoint> car;  // 51 points 0.01 map units apart
  for (int i = 0; i <= 50; ++i) car.push_back({{0.01 * i, 0, 0}, kCar, 1.0});
  const ObjectMap in_map_units = BuildObjectMap(car);
  EXPECT_EQ(in_map_units.scale_source, "map");
  const ObjectMap scaled = BuildObjectMap(car, {}, nullptr, 10.0);
  EXPECT_EQ(scaled.scale_source, "road");
  EXPECT_DOUBLE_EQ(scaled.metres_per_map_unit, 10.0);
  // 0.01 map units apart are 0.1 m: one car, 5 m long.
  ASSERT_EQ(scaled.objects.size(), 1u);
  EXPECT_NEAR(scaled.objects[0].size_m.x(), 5.0, 1e-9);
  EXPECT_THROW(BuildObjectMap(car, {}, nullptr, 0.0), InvalidArgument);
}

TEST(RoadScale, OptionsAreChecked) {
  RoadScaleOptions options;
  options.camera_height_m = 0.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.camera_height_m = std::nan("");
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.min_inliers = options.nearest_points + 1;
  EXPECT_THROW(options.Check(), InvalidArgument);
  options = {};
  options.max_tilt_deg = 90.0;
  EXPECT_THROW(options.Check(), InvalidArgument);
}

}  // namespace
}  // namespace semslam
