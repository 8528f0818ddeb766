#include "semslam/landmarks/landmark_map.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>

#include "support/test_support.h"

namespace semslam {
namespace {

using testing::TempDir;

// Map units are half metres, the map's x axis points north, y west: enu = 2 * Rz(90) * map + (10, -5, 1).
Georeference MakeGeoreference() {
  return Georeference(
      EnuFrame(Wgs84{49.0, 8.4, 100.0}),
      Sim3d(2.0, Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ())),
            Eigen::Vector3d(10.0, -5.0, 1.0)));
}

Landmark At(const Georeference& g, const std::string& name, const Eigen::Vector3d& enu, bool with_altitude) {
  Landmark l;
  l.name = name;
  l.position = g.enu_frame.ToWgs84(enu);
  l.has_altitude = with_altitude;  // without: the altitude computed here is ignored
  return l;
}

// Keyframes along the east axis every 10 m from ENU (0, 0, 3) to (100, 0, 3).
FramePositions EastwardKeyframes(const Georeference& g) {
  FramePositions keyframes;
  for (int i = 0; i <= 10; ++i) {
    FramePosition k;
    k.frame_index = static_cast<size_t>(5 * i);
    k.keyframe_id = 100 + i;
    k.timestamp = 0.5 * i;
    k.map_position = g.EnuToMap(Eigen::Vector3d(10.0 * i, 0.0, 3.0));
    keyframes.push_back(k);
  }
  return keyframes;
}

TEST(Membership, GaussianKnownValues) {
  const double sigma = 25.0;
  EXPECT_DOUBLE_EQ(GaussianMembership(0.0, sigma).value, 1.0);
  EXPECT_NEAR(GaussianMembership(0.0, sigma).pdf, 1.0 / (2 * std::numbers::pi * 625.0), 1e-15);
  EXPECT_NEAR(GaussianMembership(25.0, sigma).value, std::exp(-0.5), 1e-15);
  EXPECT_NEAR(GaussianMembership(50.0, sigma).value, std::exp(-2.0), 1e-15);
  EXPECT_NEAR(GaussianMembership(50.0, sigma).pdf, std::exp(-2.0) / (2 * std::numbers::pi * 625.0), 1e-15);
  const Membership m = GaussianMembership(Eigen::Vector2d(3, 4), Eigen::Vector2d(0, 0), 5.0);
  EXPECT_NEAR(m.value, std::exp(-0.5), 1e-15);
}

TEST(PlaceLandmarks, IntoTheMapWithNearestKeyframeAndMembership) {
  const Georeference g = MakeGeoreference();
  const FramePositions keyframes = EastwardKeyframes(g);
  const std::vector<Landmark> catalogue = {
      At(g, "North of 40", Eigen::Vector3d(41.0, 25.0, 7.0), true),  // nearest keyframe 4 at 25.02 m
      At(g, "Beyond the end", Eigen::Vector3d(160.0, 0.0, 3.0), false),
  };
  LandmarkOptions options;
  const auto placed = PlaceLandmarks(catalogue, g, keyframes, options);
  ASSERT_EQ(placed.size(), 2u);
  EXPECT_NEAR((placed[0].enu - Eigen::Vector3d(41.0, 25.0, 7.0)).norm(), 0.0, 1e-6);
  EXPECT_NEAR((g.MapToEnu(placed[0].map_position) - placed[0].enu).norm(), 0.0, 1e-9);
  // Map position by hand: map = Rz(-90) (enu - t) / 2; Rz(-90) (x, y, z) = (y, -x, z).
  EXPECT_NEAR((placed[0].map_position - Eigen::Vector3d(15.0, -15.5, 3.0)).norm(), 0.0, 1e-6);
  EXPECT_EQ(placed[0].nearest_keyframe, 4);
  EXPECT_NEAR(placed[0].keyframe_distance_m, std::hypot(1.0, 25.0), 1e-6);
  EXPECT_NEAR(placed[0].keyframe_membership.value, std::exp(-(1.0 + 625.0) / (2 * 625.0)), 1e-9);
  // No altitude in the catalogue: the nearest keyframe's.
  EXPECT_EQ(placed[1].nearest_keyframe, 10);
  EXPECT_NEAR(placed[1].enu.z(), 3.0, 1e-9);
  EXPECT_NEAR(placed[1].keyframe_distance_m, 60.0, 1e-6);

  options.max_association_distance_m = 50.0;
  const auto limited = PlaceLandmarks(catalogue, g, keyframes, options);
  EXPECT_EQ(limited[0].nearest_keyframe, 4);
  EXPECT_EQ(limited[1].nearest_keyframe, -1);
  EXPECT_NEAR(limited[1].keyframe_distance_m, 60.0, 1e-6);
  EXPECT_EQ(limited[1].keyframe_membership.value, 0.0);

  const auto none = PlaceLandmarks(catalogue, g, {}, {});
  EXPECT_EQ(none[1].nearest_keyframe, -1);
  EXPECT_EQ(none[1].enu.z(), 0.0);
  options.sigma_m = 0.0;
  EXPECT_THROW(PlaceLandmarks(catalogue, g, keyframes, options), InvalidArgument);
}

TEST(PlaceLandmarks, KeyframeTableAndNearestLandmarks) {
  const Georeference g = MakeGeoreference();
  const FramePositions keyframes = EastwardKeyframes(g);
  const auto placed = PlaceLandmarks(
      {At(g, "A", Eigen::Vector3d(0, 10, 0), true), At(g, "B", Eigen::Vector3d(100, -20, 0), true),
       At(g, "C", Eigen::Vector3d(50, 30, 0), true)},
      g, keyframes);
  const auto table = KeyframeMemberships(keyframes, placed, g, 10.0);
  ASSERT_EQ(table.size(), keyframes.size());
  ASSERT_EQ(table[0].size(), 3u);
  EXPECT_NEAR(table[0][0].value, std::exp(-0.5), 1e-9);   // 10 m at sigma 10
  EXPECT_NEAR(table[10][1].value, std::exp(-2.0), 1e-9);  // 20 m
  EXPECT_NEAR(table[5][2].value, std::exp(-4.5), 1e-9);   // 30 m

  const auto near = NearestLandmarks(g.EnuToMap(Eigen::Vector3d(90, 0, 50)), placed, g, 25.0, 2);
  ASSERT_EQ(near.size(), 2u);
  EXPECT_EQ(near[0].landmark, 1);
  EXPECT_NEAR(near[0].distance_m, std::hypot(10.0, 20.0), 1e-6);  // horizontal only
  EXPECT_NEAR(near[0].membership.value, std::exp(-500.0 / 1250.0), 1e-9);
  EXPECT_EQ(near[1].landmark, 2);
  EXPECT_EQ(NearestLandmarks(Eigen::Vector3d::Zero(), placed, g, 25.0, 10).size(), 3u);
}

TEST(MembershipRaster, GridValues) {
  const Georeference g = MakeGeoreference();
  const auto placed = PlaceLandmarks(
      {At(g, "A", Eigen::Vector3d(5, 5, 0), true), At(g, "B", Eigen::Vector3d(85, 35, 0), true)}, g, {});
  const MembershipRaster r =
      RasterizeMembership(placed, Eigen::Vector2d(0, 0), Eigen::Vector2d(100, 40), 10.0, 20.0);
  EXPECT_EQ(r.cols, 10);
  EXPECT_EQ(r.rows, 4);
  ASSERT_EQ(r.max_membership.size(), 40u);
  // Cell (0, 0) is centred on A; cell (8, 3) on B; row 0 is the south.
  EXPECT_NEAR(r.max_membership[0], 1.0, 1e-6);
  EXPECT_EQ(r.best_landmark[0], 0);
  EXPECT_NEAR(r.max_membership[3 * 10 + 8], 1.0, 1e-6);
  EXPECT_EQ(r.best_landmark[3 * 10 + 8], 1);
  // Cell (4, 1) at (45, 15): 41.2 m from A, 44.7 m from B.
  const double to_a = std::hypot(40.0, 10.0), to_b = std::hypot(40.0, 20.0);
  EXPECT_NEAR(r.max_membership[14], std::exp(-to_a * to_a / 800.0), 1e-6);
  EXPECT_EQ(r.best_landmark[14], 0);
  const double pdf =
      (std::exp(-to_a * to_a / 800.0) + std::exp(-to_b * to_b / 800.0)) / (2 * std::numbers::pi * 400.0);
  EXPECT_NEAR(r.sum_pdf[14], pdf, 1e-9);
  EXPECT_EQ(r.CellCentre(4, 1), Eigen::Vector2d(45, 15));

  // Too many cells for the budget: the cell grows.
  const MembershipRaster coarse =
      RasterizeMembership(placed, Eigen::Vector2d(0, 0), Eigen::Vector2d(100, 40), 1.0, 20.0, 100);
  EXPECT_LE(coarse.cols * coarse.rows, 100);
  EXPECT_GT(coarse.cell_m, 1.0);
  EXPECT_THROW(RasterizeMembership(placed, Eigen::Vector2d(0, 0), Eigen::Vector2d(-1, 40), 1.0, 20.0),
               InvalidArgument);
}

TEST(LandmarksGeoJsonOutput, FeaturesWithMapPositionKeyframeAndMembership) {
  const Georeference g = MakeGeoreference();
  const FramePositions keyframes = EastwardKeyframes(g);
  LandmarkOptions options;
  options.max_association_distance_m = 50.0;
  auto catalogue = std::vector<Landmark>{At(g, "Town Hall", Eigen::Vector3d(41.0, 25.0, 7.0), true),
                                         At(g, "Far", Eigen::Vector3d(300.0, 0.0, 0.0), false)};
  catalogue[0].category = "townhall";
  const auto placed = PlaceLandmarks(catalogue, g, keyframes, options);
  TempDir dir;
  WriteLandmarksGeoJson(dir / "landmarks.geojson", placed, keyframes, options.sigma_m);
  std::ifstream in(dir / "landmarks.geojson");
  const nlohmann::json root = nlohmann::json::parse(in);
  EXPECT_EQ(root["type"], "FeatureCollection");
  ASSERT_EQ(root["features"].size(), 2u);
  const auto& f = root["features"][0];
  EXPECT_EQ(f["geometry"]["type"], "Point");
  EXPECT_NEAR(f["geometry"]["coordinates"][0].get<double>(), catalogue[0].position.longitude_deg, 1e-12);
  EXPECT_NEAR(f["geometry"]["coordinates"][1].get<double>(), catalogue[0].position.latitude_deg, 1e-12);
  const auto& p = f["properties"];
  EXPECT_EQ(p["name"], "Town Hall");
  EXPECT_EQ(p["category"], "townhall");
  EXPECT_NEAR(p["map_xyz"][0].get<double>(), 15.0, 1e-6);
  EXPECT_EQ(p["nearest_keyframe"]["index"], 4);
  EXPECT_EQ(p["nearest_keyframe"]["keyframe_id"], 104);
  EXPECT_EQ(p["nearest_keyframe"]["frame_index"], 20);
  EXPECT_NEAR(p["membership"].get<double>(), placed[0].keyframe_membership.value, 1e-12);
  EXPECT_DOUBLE_EQ(p["sigma_m"].get<double>(), 25.0);
  EXPECT_TRUE(root["features"][1]["properties"]["nearest_keyframe"].is_null());
  EXPECT_EQ(root["features"][1]["geometry"]["coordinates"].size(), 2u);  // no altitude given
}

}  // namespace
}  // namespace semslam
