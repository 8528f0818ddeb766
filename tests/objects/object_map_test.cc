#include "semslam/objects/object_map.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "semslam/core/error.h"
#include "support/draws.h"
#include "support/test_support.h"

namespace semslam {
namespace {

using testing::DrawVector2;
using testing::TempDir;

constexpr int kCar = TrainId(SemanticClass::kCar);
constexpr int kPole = TrainId(SemanticClass::kPole);
constexpr int kVegetation = TrainId(SemanticClass::kVegetation);

TEST(Dbscan, KnownAnswerOnALine) {
  const Points3d points = {{0, 0, 0}, {0.5, 0, 0},  {10, 0, 0},  {1.0, 0, 0},
                           {5, 0, 0}, {10.5, 0, 0}, {1.5, 0, 0}, {11, 0, 0}};
  EXPECT_THAT(Dbscan(points, 0.6, 2), ::testing::ElementsAre(0, 0, 1, 0, -1, 1, 0, 1));
  // min_points 3: the end points of a run are border points, still in the cluster; a pair is noise.
  const Points3d pairs = {{0, 0, 0}, {0.5, 0, 0}, {1.0, 0, 0}, {7, 0, 0}, {7.5, 0, 0}};
  EXPECT_THAT(Dbscan(pairs, 0.6, 3), ::testing::ElementsAre(0, 0, 0, -1, -1));
  EXPECT_TRUE(Dbscan({}, 1.0, 3).empty());
  EXPECT_THROW(Dbscan(points, 0.0, 3), InvalidArgument);
  EXPECT_THROW(Dbscan(points, 1.0, 0), InvalidArgument);
}

// Points on a regular grid filling a box (every `step` along each axis), rotated about z by `yaw`.
std::vector<LabeledPoint> Box(const Eigen::Vector3d& center, const Eigen::Vector3d& size, double yaw,
                              int label, double step = 0.3) {
  std::vector<LabeledPoint> out;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3i n = (size / step).array().round().cast<int>();
  for (int i = 0; i <= n.x(); ++i) {
    for (int j = 0; j <= n.y(); ++j) {
      for (int k = 0; k <= n.z(); ++k) {
        const Eigen::Vector3d local =
            Eigen::Vector3d(i, j, k).cwiseProduct(size.cwiseQuotient(n.cast<double>())) - size / 2;
        out.push_back(LabeledPoint{center + r * local, label, 0.9});
      }
    }
  }
  return out;
}

struct Scene {
  std::vector<LabeledPoint> points;
  std::vector<std::vector<int>> truth;  // point indices of each true object, in order
  std::vector<int> noise;
};

// Five cars 4 x 1.8 x 1.5 m at least 8 m apart, a pole inside a bush, and 200 isolated car-labelled points.
Scene MakeScene(double map_units_per_metre) {
  Scene s;
  const auto add = [&](const std::vector<LabeledPoint>& object) {
    std::vector<int> indices;
    for (const LabeledPoint& p : object) {
      indices.push_back(static_cast<int>(s.points.size()));
      s.points.push_back(p);
    }
    s.truth.push_back(indices);
  };
  for (int i = 0; i < 5; ++i) {
    add(Box(Eigen::Vector3d(10.0 * i, 3.0 * (i % 2), 0.75), Eigen::Vector3d(4, 1.8, 1.5), 0.4 * i, kCar));
  }
  add(Box(Eigen::Vector3d(20, 20, 1), Eigen::Vector3d(3, 3, 2), 0.0, kVegetation));
  add(Box(Eigen::Vector3d(20, 20, 2), Eigen::Vector3d(0.1, 0.1, 4), 0.0, kPole, 0.1));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  while (s.noise.size() < 200) {
    const Eigen::Vector2d xy = DrawVector2(u, rng);
    const Eigen::Vector3d p(xy.x(), xy.y(), 0.5);
    bool isolated = true;  // farther than 2 m from every object point and every other noise point
    for (const LabeledPoint& q : s.points) isolated = isolated && (q.position - p).norm() > 2.0;
    if (!isolated) continue;
    s.noise.push_back(static_cast<int>(s.points.size()));
    s.points.push_back(LabeledPoint{p, kCar, 0.8});
  }
  for (LabeledPoint& p : s.points) p.position *= map_units_per_metre;
  return s;
}

TEST(ObjectMap, RecoversSyntheticClustersExactlyAndRejectsNoise) {
  const Scene s = MakeScene(1.0);
  const ObjectMap map = BuildObjectMap(s.points);
  ASSERT_EQ(map.objects.size(), 7u);
  // By class (vegetation 8 < car 13; pole 5 first), then in DBSCAN order.
  EXPECT_EQ(map.objects[0].label, kPole);
  EXPECT_EQ(map.objects[0].points, s.truth[6]);
  EXPECT_EQ(map.objects[1].label, kVegetation);
  EXPECT_EQ(map.objects[1].points, s.truth[5]);
  for (int i = 0; i < 5; ++i) {
    const SemanticObject& car = map.objects[static_cast<size_t>(2 + i)];
    EXPECT_EQ(car.label, kCar);
    EXPECT_EQ(car.points, s.truth[static_cast<size_t>(i)]) << i;
    EXPECT_EQ(car.num_points, static_cast<int>(s.truth[static_cast<size_t>(i)].size()));
    EXPECT_NEAR((car.centroid - Eigen::Vector3d(10.0 * i, 3.0 * (i % 2), 0.75)).norm(), 0.0, 1e-9);
    EXPECT_NEAR(car.mean_confidence, 0.9, 1e-12);
    // The PCA box recovers the car's size and heading.
    EXPECT_NEAR(car.size_m.x(), 4.0, 1e-6);
    EXPECT_NEAR(car.size_m.y(), 1.8, 1e-6);
    EXPECT_NEAR(car.size_m.z(), 1.5, 1e-6);
    const Eigen::Vector3d axis = car.pca_box.rotation * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::abs(axis.dot(Eigen::Vector3d(std::cos(0.4 * i), std::sin(0.4 * i), 0))), 1.0, 1e-9);
    EXPECT_NEAR((car.pca_box.center - car.centroid).norm(), 0.0, 1e-9);
    EXPECT_FALSE(car.centroid_wgs84);
  }
  EXPECT_EQ(map.noise_points[kCar], 200);
  EXPECT_EQ(map.clustered_points[kCar], static_cast<int>(s.points.size()) - 200 -
                                            static_cast<int>(s.truth[5].size() + s.truth[6].size()));
  // Axis-aligned box of the unrotated first car.
  EXPECT_NEAR((map.objects[2].box_min - Eigen::Vector3d(-2, -0.9, 0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((map.objects[2].box_max - Eigen::Vector3d(2, 0.9, 1.5)).norm(), 0.0, 1e-9);
}

TEST(ObjectMap, RadiiInMetresOnAScaledGeoreferencedMap) {
  // Map units of 0.25 m: enu = 4 * Rz(90) * map + (100, 50, 0).
  const Georeference g(
      EnuFrame(Wgs84{49.0, 8.4, 110.0}),
      Sim3d(0.25, Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ())),
            Eigen::Vector3d(100, 50, 0)));
  const Scene s = MakeScene(4.0);
  const ObjectMap map = BuildObjectMap(s.points, {}, &g);
  ASSERT_EQ(map.objects.size(), 7u);
  EXPECT_TRUE(map.georeferenced);
  const SemanticObject& car = map.objects[3];
  EXPECT_EQ(car.points, s.truth[1]);
  EXPECT_NEAR(car.size_m.x(), 4.0, 1e-6);  // metres, not map units
  ASSERT_TRUE(car.centroid_enu && car.centroid_wgs84);
  EXPECT_NEAR((*car.centroid_enu - g.MapToEnu(car.centroid)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((g.enu_frame.ToEnu(*car.centroid_wgs84) - *car.centroid_enu).norm(), 0.0, 1e-6);
  // Without the georeference the same points are taken as metres: 4x too coarse for the radii, so the
  // cars fall apart into noise.
  EXPECT_LT(BuildObjectMap(s.points).objects.size(), 7u);
}

TEST(ObjectMap, ConfidenceFilterDisabledClassesAndOptions) {
  Scene s = MakeScene(1.0);
  for (const int i : s.truth[0]) s.points[static_cast<size_t>(i)].confidence = 0.3;
  s.points.push_back(LabeledPoint{Eigen::Vector3d(0, 0, 0), kNoLabel, 1.0});
  s.points.push_back(LabeledPoint{Eigen::Vector3d(0, 0, 0), 42, 1.0});
  ObjectMapOptions options;
  options.min_confidence = 0.5;
  options.per_class[kVegetation].enabled = false;
  const ObjectMap map = BuildObjectMap(s.points, options);
  ASSERT_EQ(map.objects.size(), 5u);  // the pole and four cars
  EXPECT_EQ(map.objects[1].points, s.truth[1]);
  options.per_class[kCar].eps_m = -1;
  EXPECT_THROW(BuildObjectMap(s.points, options), InvalidArgument);
  options = {};
  options.min_confidence = 2;
  EXPECT_THROW(options.Check(), InvalidArgument);
  EXPECT_FALSE(ObjectMapOptions{}.per_class[TrainId(SemanticClass::kSky)].enabled);
}

TEST(ObjectMap, WritesObjectsJson) {
  const Georeference g(EnuFrame(Wgs84{49.0, 8.4, 110.0}), Sim3d());
  const Scene s = MakeScene(1.0);
  const ObjectMap map = BuildObjectMap(s.points, {}, &g);
  TempDir dir;
  WriteObjectsJson(dir / "objects.json", map, {});
  std::ifstream in(dir / "objects.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["format"], "semslam-objects");
  EXPECT_EQ(j["num_objects"], 7);
  EXPECT_EQ(j["counts"]["car"]["objects"], 5);
  EXPECT_EQ(j["counts"]["car"]["noise_points"], 200);
  EXPECT_EQ(j["parameters"]["traffic_sign"]["min_points"], 4);
  const auto& car = j["objects"][2];
  EXPECT_EQ(car["class"], "car");
  EXPECT_EQ(car["train_id"], kCar);
  EXPECT_EQ(car["num_points"], map.objects[2].num_points);
  EXPECT_NEAR(car["size_m"][0].get<double>(), 4.0, 1e-6);
  EXPECT_NEAR(car["centroid_wgs84"]["lat"].get<double>(), 49.0, 1e-4);
  EXPECT_EQ(car["aabb_map"]["min"].size(), 3u);
  EXPECT_EQ(car["pca_box_map"]["rotation_wxyz"].size(), 4u);
}

}  // namespace
}  // namespace semslam
