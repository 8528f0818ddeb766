#include "report_run_folder.h"

#include <opencv2/core.hpp>

#include "semslam/core/atomic_file.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/report/plots.h"

namespace semslam::report_test {

namespace fs = std::filesystem;
using json = nlohmann::json;

json RunJson() {
  return {
      {"sequence", "/data/city/sequences/00"},
      {"mode", "mono"},
      {"frames", 100},
      {"first_frame", 0},
      {"tracked", 98},
      {"keyframes", 20},
      {"points", 5000},
      {"loops", 1},
      {"relocalizations", 2},
      {"resets", 0},
      {"seconds", 5.0},
      {"ate_rmse", 0.25},
      {"ate_alignment", "sim3"},
      {"ate_matched", 98},
      {"path_length_m", 100.0},
      {"intrinsics_refinement",
       json::array(
           {{{"map", 0},
             {"accepted", true},
             {"nominal", {{"fx", 707.0912}, {"fy", 707.0912}, {"cx", 601.9}, {"cy", 183.1}}},
             {"refined",
              {{"fx", 699.9}, {"fy", 699.9}, {"cx", 601.1}, {"cy", 185.3}, {"k1", 0.0148}, {"k2", -0.0066}}},
             {"plain_cost", 8395.0},
             {"refined_cost", 8159.0}}})},
      {"classes", {{"road", 2000}, {"building", 2500}, {"car", 400}, {"unlabeled", 100}}},
      {"segmentation",
       {{"segmenter", "truth-noisy labels"},
        {"segmented_keyframes", 20},
        {"segmented_frames", 60},
        {"median_ms", 40.0}}},
      {"label_accuracy", 0.92},
      {"label_accuracy_3d_global", 0.92},
      {"label_accuracy_3d", 0.94},
      {"label_accuracy_2d", 0.96},
      {"label_evaluation",
       {{"surface_points", {{"accuracy", 0.94}, {"evaluated", 4100}}},
        {"fused_points",
         {{"accuracy", 0.96},
          {"evaluated", 4900},
          {"per_class", {{"road", {{"accuracy", 0.97}, {"evaluated", 2000}}}}}}},
        {"single_frame_keypoints", {{"accuracy", 0.75}, {"evaluated", 9000}}}}},
      {"geo",
       {{"georeferenced", true},
        {"fused", true},
        {"gps_fixes", 100},
        {"gps_format", "oxts"},
        {"gps_samples", 4},
        {"gps_inliers", 4},
        {"single_sim3_rmse_m", 1.5},
        {"fused_rmse_m", 1.2},
        {"metres_per_map_unit", 30.0},
        {"landmarks", 2},
        {"landmarks_associated", 2},
        {"topology_nodes", 3},
        {"topology_edges", 2},
        {"objects", 3}}},
      {"geo_evaluation",
       {{"landmark_error_median_m", 0.8},
        {"landmark_error_max_m", 1.4},
        {"landmark_errors", {{{"name", "Town Hall"}, {"error_m", 0.8}, {"horizontal_m", 0.5}}}}}},
  };
}

json TimingJson() {
  auto module = [](int count, double median) {
    return json{{"count", count},         {"median_ms", median},  {"mean_ms", median * 1.1},
                {"p95_ms", median * 2.0}, {"max_ms", median * 3}, {"total_ms", median * count}};
  };
  return {{"tracking", module(100, 25.0)},
          {"orb_extraction", module(100, 15.0)},
          {"label_fusion", module(60, 0.04)},
          {"local_mapping", module(20, 200.0)},
          {"loop_closing", module(19, 0.5)}};
}

std::vector<SemanticPoint> MapPoints(int count) {
  std::vector<SemanticPoint> points;
  for (int i = 0; i < count; ++i) {
    SemanticPoint p;
    p.position = Eigen::Vector3d(0.01 * i, -0.5 + 0.001 * (i % 100), 0.02 * i);
    p.label = i % 50 == 0 ? kNoLabel : (i % 3 == 0 ? 0 : (i % 3 == 1 ? 2 : 13));
    p.confidence = 0.9f;
    p.observations = 3;
    points.push_back(p);
  }
  return points;
}

Trajectory Poses(int count) {
  Trajectory trajectory;
  for (int i = 0; i < count; ++i) {
    trajectory.push_back(
        {0.1 * i, Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, 0.5 * i))});
  }
  return trajectory;
}

json LandmarksGeoJson() {
  auto feature = [](const std::string& name, double lon, double lat, bool associated) {
    json properties = {{"name", name},
                       {"category", "civic"},
                       {"map_xyz", {1.0, -0.2, 3.0}},
                       {"membership", 0.5},
                       {"sigma_m", 25.0}};
    if (associated) {
      properties["nearest_keyframe"] = {{"keyframe_id", 7}, {"frame_index", 35}, {"distance_m", 29.4}};
    }
    return json{{"type", "Feature"},
                {"geometry", {{"type", "Point"}, {"coordinates", {lon, lat, 100.0}}}},
                {"properties", properties}};
  };
  return {{"type", "FeatureCollection"},
          {"features",
           {feature("Town Hall", 8.4, 49.0, true), feature(std::string(kTrickyName), 8.41, 49.01, false)}}};
}

json ObjectsJson() {
  json objects = json::array();
  for (int i = 0; i < 3; ++i) {
    objects.push_back({{"id", i},
                       {"class", i == 0 ? "building" : "car"},
                       {"num_points", 40 + i},
                       {"size_m", {4.0, 2.0, 1.5}},
                       {"centroid_map", {0.1 * i, 0.0, 1.0}},
                       {"centroid_enu", {3.0 * i, 1.0, 0.0}},
                       {"centroid_wgs84", {{"lat", 49.0}, {"lon", 8.4}, {"alt", 100.0}}},
                       {"mean_confidence", 0.9}});
  }
  return {{"format", "semslam-objects"}, {"num_objects", 3}, {"objects", objects}};
}

void WriteJson(const fs::path& file, const json& value) { WriteFileAtomically(file, value.dump(1)); }

void WriteFullRun(const fs::path& dir, int points, int poses) {
  WriteJson(dir / "run.json", RunJson());
  WriteJson(dir / "timing.json", TimingJson());
  WriteSemanticPly(dir / "semantic_map.ply", MapPoints(points));
  WriteTumTrajectory(dir / "trajectory.tum", Poses(poses));
  WriteTumTrajectory(dir / "keyframes.tum", Poses(poses / 5));
  WriteJson(dir / "landmarks.geojson", LandmarksGeoJson());
  WriteJson(dir / "objects.json", ObjectsJson());
  cv::Mat image(40, 60, CV_8UC3, cv::Scalar(255, 255, 255));
  WritePlot(dir / "plots" / "gps.png", image);
  WritePlot(dir / "plots" / "topology.png", image);
}

}  // namespace semslam::report_test
