// WriteGeoOutputs end to end on a drifting monocular drive around a block (tests/geo/synthetic_drive.h), and
// its evaluation against the drive's truth.

#include "semslam/report/geo_outputs.h"

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>

#include "geo/synthetic_drive.h"
#include "semslam/core/error.h"
#include "semslam/report/geo_evaluation.h"
#include "semslam/topology/routing.h"
#include "support/test_support.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using testing::Drive;
using ::testing::HasSubstr;
using testing::MakeDrive;
using testing::TempDir;

struct NamedPlace {
  const char* name;
  Eigen::Vector3d enu;
};
const NamedPlace kPlaces[] = {{"Town Hall", {100, -15, 2}},
                              {"Library", {410, 310, 0}},
                              {"Cafe", {212, 140, 0}},
                              {"Museum", {-12, 150, 1}},
                              {"Far Away", {1000, 1000, 0}}};

std::string Read(const fs::path& p) {
  std::ifstream in(p);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The inputs `semslam run` would give: every frame, keyframes every 5 frames, GPS as a CSV log, a landmark
// catalogue, and labeled points of two parked cars placed in the drifting map.
struct Scenario {
  Drive drive;
  GeoInputs inputs;
  SceneTruth truth;
  std::vector<std::vector<int>> car_points;

  Scenario(const fs::path& dir, double outlier_fraction, unsigned seed)
      : drive(MakeDrive(0.01, 0.2, 0.05, 1.0, 30, outlier_fraction, seed)) {
    inputs.frames = drive.frames;
    for (size_t i = 0; i < drive.frames.size(); i += 5) {
      FramePose k = drive.frames[i];
      k.keyframe_id = static_cast<long long>(inputs.keyframes.size());
      inputs.keyframes.push_back(k);
    }
    std::string gps = "t,lat,lon,alt,sigma\n";
    for (const GpsFix& f : drive.fixes) {
      gps += fmt::format("{:.3f},{:.10f},{:.10f},{:.4f},1.0\n", f.timestamp, f.position.latitude_deg,
                         f.position.longitude_deg, f.position.altitude_m);
    }
    std::ofstream(dir / "gps.csv") << gps;
    inputs.gps_path = dir / "gps.csv";
    std::string catalogue = "name,lat,lon,alt,category\n";
    for (const NamedPlace& p : kPlaces) {
      const Wgs84 w = drive.enu.ToWgs84(p.enu);
      catalogue += fmt::format("{},{:.10f},{:.10f},{:.3f},building\n", p.name, w.latitude_deg,
                               w.longitude_deg, w.altitude_m);
    }
    std::ofstream(dir / "landmarks.csv") << catalogue;
    inputs.landmarks_path = dir / "landmarks.csv";
    // Two cars (4 x 2 x 1.5 m, a point every 0.25 m) beside the first street, in the map through the nearest
    // frame.
    for (const Eigen::Vector3d& centre : {Eigen::Vector3d(50, 6, 0.75), Eigen::Vector3d(300, -6, 0.75)}) {
      std::vector<int> indices;
      const size_t frame = static_cast<size_t>(centre.x());  // the first street: a frame per metre
      const Rigid3d& truth_pose = drive.truth[frame];
      const Rigid3d& map_pose = drive.frames[frame].world_from_camera;
      for (double x = -2; x <= 2; x += 0.25) {
        for (double y = -1; y <= 1; y += 0.25) {
          for (double z = -0.75; z <= 0.75; z += 0.25) {
            const Eigen::Vector3d in_camera = truth_pose.Inverse() * (centre + Eigen::Vector3d(x, y, z));
            indices.push_back(static_cast<int>(inputs.points.size()));
            inputs.points.push_back(LabeledPoint{map_pose * (drive.map_scale[frame] * in_camera),
                                                 TrainId(SemanticClass::kCar), 0.9});
          }
        }
      }
      car_points.push_back(indices);
    }
    // The truth as scene.json would give it: world = the first camera.
    truth.origin = drive.enu.origin();
    truth.enu_from_world = drive.truth[0];
    for (const Rigid3d& t : drive.truth) {
      truth.world_from_camera.push_back(drive.truth[0].Inverse() * t);
      truth.positions_world.push_back(truth.world_from_camera.back().translation);
    }
    for (const NamedPlace& p : kPlaces) truth.landmarks.push_back({p.name, "building", p.enu, 0});
  }
};

TEST(GeoOutputs, WritesEverythingForADriftingMonocularDrive) {
  TempDir dir;
  const Scenario s(dir.path(), 0.0, 11);
  const fs::path out = dir / "out";
  const GeoOutputs outputs = WriteGeoOutputs(s.inputs, out);
  ASSERT_TRUE(outputs.georeference);
  ASSERT_TRUE(outputs.fusion);
  EXPECT_TRUE(outputs.summary.fused);
  EXPECT_EQ(outputs.summary.gps_format, "csv");
  EXPECT_EQ(outputs.summary.gps_fixes, static_cast<int>(s.drive.fixes.size()));
  EXPECT_EQ(outputs.summary.gps_samples, static_cast<int>(s.drive.fixes.size()));
  EXPECT_NEAR(outputs.summary.metres_per_map_unit, 20.0 / 1.09, 2.5);  // the drift's mean over the route

  for (const char* name :
       {"trajectory_wgs84.csv", "landmarks.geojson", "topology.geojson", "topology.graphml", "topology.dot",
        "topology.json", "objects.json", "georeference.json", "plots/gps.png", "plots/topology.png",
        "plots/semantic_map.png", "plots/membership.png", "plots/trajectory.png"}) {
    EXPECT_TRUE(fs::is_regular_file(out / name)) << name;
    EXPECT_GT(fs::file_size(out / name), 100u) << name;
  }
  EXPECT_EQ(outputs.files.size(), 13u);
  const std::string csv = Read(out / "trajectory_wgs84.csv");
  EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), static_cast<long>(s.drive.frames.size()) + 1);
  EXPECT_EQ(csv.substr(0, 14), "t,lat,lon,alt\n");

  // Landmarks: all five placed; the far one without a node.
  ASSERT_EQ(outputs.landmarks.size(), 5u);
  EXPECT_EQ(outputs.summary.landmarks, 5);
  const nlohmann::json geojson = nlohmann::json::parse(Read(out / "landmarks.geojson"));
  EXPECT_EQ(geojson["features"].size(), 5u);
  EXPECT_EQ(geojson["features"][0]["properties"]["name"], "Town Hall");
  EXPECT_NEAR(geojson["features"][0]["properties"]["membership"].get<double>(), std::exp(-15.0 * 15 / 1250.0),
              0.1);

  // Topology: the four landmark nodes (the library at a corner) and the turns: four corners of the block,
  // the start corner again, and the last turn north; the town hall and the start corner are passed twice.
  ASSERT_TRUE(outputs.topology);
  EXPECT_EQ(outputs.summary.topology_landmark_nodes, 4);
  EXPECT_EQ(outputs.summary.topology_turn_nodes, 5);
  EXPECT_GE(outputs.summary.topology_revisited_nodes, 2);
  const Route route = FindRoute(*outputs.topology, "Town Hall", "Museum");
  EXPECT_NEAR(route.length_m, 100 + 150, 10.0);  // west along the first street, then north

  // Objects: the two cars, recovered exactly.
  ASSERT_EQ(outputs.objects.objects.size(), 2u);
  EXPECT_EQ(outputs.objects.objects[0].points, s.car_points[0]);
  EXPECT_EQ(outputs.objects.objects[1].points, s.car_points[1]);
  ASSERT_TRUE(outputs.objects.objects[0].centroid_enu);
  EXPECT_NEAR((*outputs.objects.objects[0].centroid_enu - Eigen::Vector3d(50, 6, 0.75)).norm(), 0.0, 1.5);
  EXPECT_EQ(outputs.summary.objects_per_class.at("car"), 2);

  // Summary JSON and the map file's sections.
  const nlohmann::json summary = nlohmann::json::parse(outputs.summary.ToJson());
  EXPECT_EQ(summary["topology_turn_nodes"], 5);
  ASSERT_EQ(outputs.map_sections.count("topology"), 1u);
  EXPECT_EQ(ParseTopologyJson(outputs.map_sections.at("topology"), "section").nodes.size(),
            outputs.topology->nodes.size());

  // Evaluation against the truth: the bars (landmarks <= 2 m, WGS84 trajectory <= 1.5 m).
  const GeoEvaluation e = EvaluateGeo(outputs, s.inputs, s.truth);
  std::printf(
      "BlockLoop, 1 %%/100 m scale drift, sigma 1 m every 30 frames, fused: trajectory ATE %.2f m (max "
      "%.2f), "
      "landmarks median %.2f m, max %.2f m (%d)\n",
      e.trajectory_ate_rmse_m, e.trajectory_ate_max_m, e.landmark_error_median_m, e.landmark_error_max_m,
      e.landmarks);
  for (const auto& l : e.landmark_errors)
    std::printf("  %s %.2f m (horizontal %.2f m)\n", l.name.c_str(), l.error_m, l.horizontal_m);
  EXPECT_EQ(e.trajectory_frames, static_cast<int>(s.drive.frames.size()));
  EXPECT_LT(e.trajectory_ate_rmse_m, 1.5);
  EXPECT_EQ(e.landmarks, 4);
  EXPECT_EQ(e.landmarks_too_far, 1);  // "Far Away"
  EXPECT_LT(e.landmark_error_median_m, 2.0);
  EXPECT_LT(e.landmark_error_max_m, 2.0);
  EXPECT_EQ(nlohmann::json::parse(e.ToJson())["landmarks"], 4);
}

TEST(GeoOutputs, SingleSimilarityAndOutliers) {
  TempDir dir;
  const Scenario s(dir.path(), 0.05, 12);
  GeoOptions options;
  options.write_plots = false;
  const GeoOutputs fused = WriteGeoOutputs(s.inputs, dir / "fused", options);
  options.fuse = false;
  const GeoOutputs single = WriteGeoOutputs(s.inputs, dir / "single", options);
  ASSERT_TRUE(fused.georeference && single.georeference);
  EXPECT_FALSE(single.fusion);
  EXPECT_FALSE(single.georeference->local);
  const GeoEvaluation ef = EvaluateGeo(fused, s.inputs, s.truth);
  const GeoEvaluation es = EvaluateGeo(single, s.inputs, s.truth);
  std::printf(
      "with 5 %% 50 m outliers: trajectory ATE fused %.2f m, single Sim(3) %.2f m; landmarks median fused "
      "%.2f "
      "m, single %.2f m\n",
      ef.trajectory_ate_rmse_m, es.trajectory_ate_rmse_m, ef.landmark_error_median_m,
      es.landmark_error_median_m);
  EXPECT_LT(ef.trajectory_ate_rmse_m, 1.5);
  EXPECT_GT(es.trajectory_ate_rmse_m, 3.0);
  EXPECT_LT(ef.landmark_error_median_m, 2.0);
  EXPECT_FALSE(fs::exists(dir / "fused" / "plots"));
}

TEST(GeoOutputs, LocalizeThroughTheMapSection) {
  TempDir dir;
  const Scenario s(dir.path(), 0.0, 13);
  GeoOptions options;
  options.write_plots = false;
  const GeoOutputs outputs = WriteGeoOutputs(s.inputs, dir / "out", options);
  ASSERT_EQ(outputs.map_sections.count("geo"), 1u);
  const GeoContext context = ParseGeoSection(outputs.map_sections.at("geo"), "map.semslam#geo", 7);
  ASSERT_EQ(context.landmarks.size(), 5u);
  ASSERT_EQ(context.maps.size(), 1u);
  EXPECT_EQ(context.landmarks_map, s.inputs.map_id);
  const Georeference* georeference = context.Of(s.inputs.map_id);
  ASSERT_NE(georeference, nullptr);
  ASSERT_TRUE(georeference->local);
  EXPECT_EQ(context.Of(s.inputs.map_id + 1), nullptr);
  // Frame 95 (95 m along the first street, heading east), 5 m from the town hall's nearest point.
  const FramePose& frame = s.drive.frames[95];
  const GeoPose pose = LocateInWorld(frame.world_from_camera, *georeference, context, true, 2);
  const EnuFrame truth_enu(s.truth.origin);
  EXPECT_NEAR((truth_enu.ToEnu(pose.wgs84) - s.drive.truth_enu[95]).norm(), 0.0, 1.5);
  EXPECT_NEAR(pose.heading_deg, 90.0, 3.0);
  ASSERT_EQ(pose.nearest.size(), 2u);
  EXPECT_EQ(pose.nearest[0].name, "Town Hall");
  EXPECT_NEAR(pose.nearest[0].distance_m, std::hypot(5.0, 15.0), 1.5);
  EXPECT_NEAR(pose.nearest[0].membership.value, std::exp(-250.0 / 1250.0), 0.05);
  // Landmarks placed in another map are not near a pose of this one.
  EXPECT_TRUE(LocateInWorld(frame.world_from_camera, *georeference, context, false, 2).nearest.empty());

  // A version-1 section (one georeference, the file's single map) is read as the georeference of map 7.
  nlohmann::json v1 = nlohmann::json::parse(outputs.map_sections.at("geo"));
  v1["version"] = 1;
  v1["georeference"] = v1["maps"][0]["georeference"];
  v1.erase("maps");
  v1.erase("landmarks_map");
  const GeoContext old = ParseGeoSection(v1.dump(), "map.semslam#geo", 7);
  ASSERT_NE(old.Of(7), nullptr);
  EXPECT_EQ(old.landmarks_map, 7u);
  EXPECT_NEAR(old.Of(7)->enu_from_map.scale, georeference->enu_from_map.scale, 1e-9);

  EXPECT_THROW(ParseGeoSection("{\"format\": \"other\"}", "x", 0), InputError);
  nlohmann::json broken = nlohmann::json::parse(outputs.map_sections.at("geo"));
  broken["maps"][0]["georeference"]["enu_from_map"]["scale"] = -1;
  try {
    ParseGeoSection(broken.dump(), "map.semslam#geo", 0);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("enu_from_map.scale"));
  }
  nlohmann::json twice = nlohmann::json::parse(outputs.map_sections.at("geo"));
  twice["maps"].push_back(twice["maps"][0]);
  try {
    ParseGeoSection(twice.dump(), "map.semslam#geo", 0);
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("given twice"));
  }
}

TEST(GeoOutputs, WithoutGpsOnlyObjectsAndTheSemanticMap) {
  TempDir dir;
  Scenario s(dir.path(), 0.0, 14);
  s.inputs.gps_path.clear();
  const GeoOutputs outputs = WriteGeoOutputs(s.inputs, dir / "out");
  EXPECT_FALSE(outputs.georeference);
  EXPECT_FALSE(outputs.topology);
  EXPECT_TRUE(fs::exists(dir / "out" / "objects.json"));
  EXPECT_TRUE(fs::exists(dir / "out" / "plots" / "semantic_map.png"));
  EXPECT_FALSE(fs::exists(dir / "out" / "trajectory_wgs84.csv"));
  EXPECT_FALSE(outputs.summary.georeferenced);
  // No road labelled: the objects stay in map units.
  EXPECT_EQ(outputs.summary.objects_scale_source, "map");
  EXPECT_EQ(outputs.objects.metres_per_map_unit, 1.0);

  s.inputs.gps_path = dir / "missing.csv";
  EXPECT_THROW(WriteGeoOutputs(s.inputs, dir / "out2"), InputError);
  s.inputs.gps_path.clear();
  std::swap(s.inputs.keyframes[1], s.inputs.keyframes[2]);
  EXPECT_THROW(WriteGeoOutputs(s.inputs, dir / "out3"), InvalidArgument);
}

TEST(GeoOutputs, AMonocularMapWithoutGpsScalesItsObjectsByTheRoad) {
  TempDir dir;
  Scenario s(dir.path(), 0.0, 14);
  s.inputs.gps_path.clear();
  // Road points 3-15 m ahead of each keyframe, 1.65 m beneath its camera, placed in the drifting map as the
  // cars are.
  std::vector<double> map_scales;
  for (const FramePose& kf : s.inputs.keyframes) {
    const double map_scale = s.drive.map_scale[kf.frame_index];
    map_scales.push_back(map_scale);
    for (double x = -3; x <= 3; x += 1.5) {
      for (double z = 3; z <= 15; z += 2) {
        s.inputs.points.push_back(
            LabeledPoint{kf.world_from_camera * (map_scale * Eigen::Vector3d(x, 1.65, z)),
                         TrainId(SemanticClass::kRoad), 0.9});
      }
    }
  }
  std::nth_element(map_scales.begin(), map_scales.begin() + map_scales.size() / 2, map_scales.end());
  const double metres_per_map_unit = 1.0 / map_scales[map_scales.size() / 2];
  const GeoOutputs outputs = WriteGeoOutputs(s.inputs, dir / "out");
  EXPECT_EQ(outputs.summary.objects_scale_source, "road");
  EXPECT_EQ(outputs.summary.road_scale_keyframes, static_cast<int>(s.inputs.keyframes.size()));
  // Measured 0.9 % above the median of the map's scales at the keyframes (spread 6.8 %: the scale drifts 1 %
  // per 100 m): each fit takes in the road of the keyframes beside it too.
  const double estimated = outputs.summary.objects_metres_per_map_unit;
  EXPECT_NEAR(estimated, metres_per_map_unit, 0.015 * metres_per_map_unit);
  const nlohmann::json objects = nlohmann::json::parse(Read(dir / "out" / "objects.json"));
  EXPECT_EQ(objects["scale_source"], "road");
  // The two 4 x 2 x 1.5 m cars, in metres as the one scale gives them where the map's scale has drifted (50 m
  // and 300 m along the drive).
  const auto is_car = [](const SemanticObject& o) { return o.label == TrainId(SemanticClass::kCar); };
  ASSERT_EQ(std::count_if(outputs.objects.objects.begin(), outputs.objects.objects.end(), is_car), 2);
  for (const SemanticObject& car : outputs.objects.objects) {
    if (!is_car(car)) continue;
    const size_t frame = car.points == s.car_points[0] ? 50 : 300;
    const double local = estimated * s.drive.map_scale[frame];  // the car's metres per true metre
    EXPECT_NEAR(car.size_m.x(), 4.0 * local, 0.01);
    EXPECT_NEAR(car.size_m.y(), 2.0 * local, 0.01);
  }
}

}  // namespace
}  // namespace semslam
