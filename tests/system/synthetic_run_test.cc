// `semslam synth` then `semslam run` on the synthetic city (200 frames, ~195 m, one left turn, eight
// landmarks), judged against the city's ground truth: poses, GPS truth and landmark positions (the map's
// labels: synthetic_run_labels_test.cc).
//
// One monocular run (with truth-noisy:0.25 segmentation, GPS and landmarks) and one stereo run serve every
// test here and there; both are made once per semslam binary (system_test_util.h).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "semslam/eval/trajectory_metrics.h"
#include "semslam/geo/wgs84.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/semantic_outputs.h"
#include "semslam/sim/scene_file.h"
#include "semslam/sim/synthetic_city.h"
#include "support/test_support.h"
#include "system_test_util.h"

namespace semslam::system_test {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

// Bounds, measured on the development machine (seed 1; seeds 2 and 3 for the spread) with a margin of 3-5x.
// Monocular ATE after Sim(3) alignment, as a fraction of the path length: measured 0.05 % (0.106 m over 202
// m; seeds 2 and 3: 0.128 m and 0.033 m); on the route with a car's yaw rate (issue 9) 0.103 m over 195 m.
constexpr double kMonoAteFractionOfPath = 0.0025;
// Stereo ATE after SE(3) alignment: measured 0.065 m (seeds 2, 3: 0.057 m, 0.033 m; 0.066 m on the new
// route); Sim(3) scale 1.0012.
constexpr double kStereoAteM = 0.25;
constexpr double kStereoScaleTolerance = 0.01;

std::vector<double> SequenceTimes(const fs::path& dataset) {
  return ReadTimes(SequenceDir(dataset) / "times.txt");
}

// The first frame from which every frame to the end is tracked (num_frames when the last one is not).
int TrackedFromFrame(const std::vector<int>& frames, int num_frames) {
  std::set<int> tracked(frames.begin(), frames.end());
  int first = num_frames;
  while (first > 0 && tracked.count(first - 1)) --first;
  return first;
}

double ArcLengthTo(const std::vector<Rigid3d>& poses, int frame) {
  double length = 0.0;
  for (int i = 1; i <= frame; ++i) {
    length +=
        (poses[static_cast<size_t>(i)].translation - poses[static_cast<size_t>(i - 1)].translation).norm();
  }
  return length;
}

class SyntheticRun : public ::testing::Test {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
};

TEST_F(SyntheticRun, MonoWritesEveryOutputAndSummary) {
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  for (const char* file : {"trajectory.tum", "keyframes.tum", "trajectory.kitti", "map.semslam",
                           "semantic_map.ply", "timing.json", "run.json"}) {
    EXPECT_TRUE(fs::exists(run / file)) << file;
    if (fs::exists(run / file)) {
      EXPECT_GT(fs::file_size(run / file), 0u) << file;
    }
  }
  const nlohmann::json j = ReadJson(run / "run.json");
  ASSERT_TRUE(j.is_object()) << ReadText(run / "run.json");
  EXPECT_EQ(j.value("mode", ""), "mono");
  EXPECT_EQ(j.value("frames", -1), kSyntheticFrames);
  for (const char* key : {"tracked", "keyframes", "points", "loops"}) {
    ASSERT_TRUE(j.contains(key) && j[key].is_number_integer()) << key;
  }
  ASSERT_TRUE(j.contains("ate_rmse") && j["ate_rmse"].is_number());
  EXPECT_GT(j["keyframes"].get<int>(), 10);
  EXPECT_GT(j["points"].get<int>(), 1000);
  EXPECT_EQ(j["loops"].get<int>(), 0);  // 200 frames of this town revisit nothing
  EXPECT_EQ(j.value("resets", -1), 0);
  // Per-class counts: every class key, summing to the points.
  ASSERT_TRUE(j.contains("classes") && j["classes"].is_object());
  long long sum = 0;
  for (int c = 0; c < kNumClasses; ++c) {
    const std::string key(ClassKey(c));
    ASSERT_TRUE(j["classes"].contains(key)) << key;
    sum += j["classes"][key].get<long long>();
  }
  sum += j["classes"].value("unlabeled", 0LL);
  EXPECT_EQ(sum, j["points"].get<long long>());

  // The final BA's self-calibration reports on the one map; the city's camera is exact, so whatever it
  // decided, the camera it found is within a fraction of a percent of the true one.
  ASSERT_TRUE(j.contains("intrinsics_refinement") && j["intrinsics_refinement"].size() == 1)
      << j.value("intrinsics_refinement", nlohmann::json()).dump();
  const nlohmann::json& refinement = j["intrinsics_refinement"][0];
  const double nominal_fx = refinement["nominal"]["fx"].get<double>();
  EXPECT_NEAR(refinement["refined"]["fx"].get<double>(), nominal_fx, 0.005 * nominal_fx);
  EXPECT_LE(refinement["refined_cost"].get<double>(), refinement["plain_cost"].get<double>());
  EXPECT_EQ(refinement.contains("reason"), !refinement["accepted"].get<bool>());

  // timing.json: per-module times, tracking once per frame.
  const nlohmann::json timing = ReadJson(run / "timing.json");
  ASSERT_TRUE(timing.is_object() && timing.contains("tracking")) << ReadText(run / "timing.json");
  EXPECT_EQ(timing["tracking"].value("count", -1), kSyntheticFrames);
  for (const char* module : {"orb_extraction", "local_mapping", "label_fusion"}) {
    EXPECT_TRUE(timing.contains(module)) << module;
  }
}

TEST_F(SyntheticRun, MonoInitializesEarlyTracksEveryFrameAndIsAccurate) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  const nlohmann::json j = ReadJson(run / "run.json");
  const Trajectory trajectory = ReadTumTrajectory(run / "trajectory.tum");
  const std::vector<double> times = SequenceTimes(data);
  const std::vector<int> frames = FrameIndices(Timestamps(trajectory), times);
  // Timestamps come from times.txt, in frame order.
  for (size_t i = 0; i < frames.size(); ++i) {
    ASSERT_GE(frames[i], 0) << "trajectory.tum pose " << i << " has a timestamp not in times.txt";
    if (i > 0) {
      ASSERT_GT(frames[i], frames[i - 1]);
    }
  }
  // Initialized within the first 10 frames, then every frame tracked (measured: from frames 0 and 2).
  EXPECT_LE(TrackedFromFrame(frames, kSyntheticFrames), 10);
  const int tracked = j["tracked"].get<int>();
  EXPECT_GE(tracked, static_cast<int>(0.95 * kSyntheticFrames));
  // Every tracked frame has a pose, and so have the frames the map started from.
  EXPECT_GE(static_cast<int>(trajectory.size()), tracked);
  EXPECT_EQ(static_cast<int>(trajectory.size()), j["with_pose"].get<int>());

  // ATE (Sim(3)), against a bound measured with margin.
  const double path = j.value("path_length_m", 0.0);
  EXPECT_NEAR(path, 195.1, 1.0);  // 202.2 m before the route took its turns at a car's yaw rate (issue 9)
  const double ate = j["ate_rmse"].get<double>();
  EXPECT_EQ(j.value("ate_alignment", ""), "sim3");
  EXPECT_LE(ate, kMonoAteFractionOfPath * path) << "ATE " << ate << " m over " << path << " m";
  EXPECT_GT(ate, 0.0);

  // Our own ATE from the files agrees.
  const TrajectoryEvaluation mine = EvaluateTrajectoryFiles(run / "trajectory.tum", data / "poses" / "00.txt",
                                                            SequenceDir(data) / "times.txt");
  EXPECT_EQ(mine.matched, trajectory.size());
  EXPECT_NEAR(mine.ate.rmse, ate, 1e-4);
}

TEST_F(SyntheticRun, EvalCommandAgreesWithRunJson) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  const CommandResult r = RunSemslam({"eval", "--estimate", (run / "trajectory.tum").string(), "--truth",
                                      (data / "poses" / "00.txt").string(), "--times",
                                      (SequenceDir(data) / "times.txt").string()});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const nlohmann::json e = nlohmann::json::parse(r.out, nullptr, false);
  ASSERT_TRUE(e.is_object()) << r.out;
  const nlohmann::json j = ReadJson(run / "run.json");
  EXPECT_EQ(e.value("alignment", ""), "sim3");
  EXPECT_NEAR(e["ate_rmse"].get<double>(), j["ate_rmse"].get<double>(), 1e-4);
  EXPECT_NEAR(e["scale"].get<double>(), j["ate_scale"].get<double>(), 1e-3 * j["ate_scale"].get<double>());
  EXPECT_EQ(e["matched"].get<int>(), j["ate_matched"].get<int>());
  EXPECT_NEAR(e["path_length_m"].get<double>(), j["path_length_m"].get<double>(), 0.5);
}

TEST_F(SyntheticRun, MonoOutputFilesAgreeWithEachOther) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  const nlohmann::json j = ReadJson(run / "run.json");
  const Trajectory tum = ReadTumTrajectory(run / "trajectory.tum");
  // trajectory.kitti: one line per frame (line i = frame i), the tracked frames' poses on their lines.
  const std::vector<Rigid3d> kitti = ReadKittiPoses(run / "trajectory.kitti");
  ASSERT_EQ(kitti.size(), static_cast<size_t>(kSyntheticFrames));
  std::vector<double> stamps;
  for (const StampedPose& p : tum) stamps.push_back(p.timestamp);
  const std::vector<int> frames =
      FrameIndices(stamps, ReadTimes(SequenceDir(SyntheticDataset().dir) / "times.txt"));
  for (size_t i = 0; i < tum.size(); ++i) {
    ASSERT_GE(frames[i], 0) << i;
    ASSERT_LT(
        (kitti[static_cast<size_t>(frames[i])].translation - tum[i].world_from_camera.translation).norm(),
        1e-4)
        << i;
  }
  // Keyframes: as many as run.json says, each at the time of a tracked frame, at that frame's pose.
  const Trajectory keyframes = ReadTumTrajectory(run / "keyframes.tum");
  EXPECT_EQ(static_cast<int>(keyframes.size()), j["keyframes"].get<int>());
  std::map<long long, Eigen::Vector3d> by_time;
  for (const StampedPose& p : tum)
    by_time[std::llround(p.timestamp * 1000)] = p.world_from_camera.translation;
  for (const StampedPose& k : keyframes) {
    const auto it = by_time.find(std::llround(k.timestamp * 1000));
    ASSERT_NE(it, by_time.end()) << "keyframe at " << k.timestamp << " is not a tracked frame";
    EXPECT_LT((it->second - k.world_from_camera.translation).norm(), 1e-6) << k.timestamp;
  }
  // The semantic point cloud has the map's points.
  const std::vector<SemanticPoint> ply = ReadSemanticPly(run / "semantic_map.ply");
  EXPECT_EQ(static_cast<long long>(ply.size()), j["points"].get<long long>());
}

// Semantics: truth-noisy:0.25 makes single segmentations 75 % right; fusing them into map points over the
// keyframes that see each point must make >= 95 % of the points right (SPEC bar).
TEST_F(SyntheticRun, GpsLandmarksTopologyObjectsAndPlots) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  for (const char* file : {"trajectory_wgs84.csv", "landmarks.geojson", "topology.geojson",
                           "topology.graphml", "topology.dot", "topology.json", "objects.json"}) {
    ASSERT_TRUE(fs::exists(run / file)) << file;
    EXPECT_GT(fs::file_size(run / file), 0u) << file;
  }
  int plots = 0;
  for (const auto& entry : fs::directory_iterator(run / "plots")) {
    if (entry.path().extension() != ".png") continue;
    ++plots;
    const cv::Mat image = cv::imread(entry.path().string());
    EXPECT_FALSE(image.empty()) << entry.path();
    EXPECT_GE(image.cols, 200) << entry.path();
  }
  EXPECT_GE(plots, 3);
  for (const char* plot : {"gps.png", "topology.png", "semantic_map.png"}) {
    EXPECT_TRUE(fs::exists(run / "plots" / plot)) << plot;
  }

  const nlohmann::json j = ReadJson(run / "run.json");
  ASSERT_TRUE(j.contains("geo_evaluation")) << j.dump(2);
  const nlohmann::json& geo = j["geo"];
  EXPECT_TRUE(geo.value("georeferenced", false));
  EXPECT_EQ(geo.value("gps_format", ""), "oxts");
  EXPECT_EQ(geo.value("gps_fixes", 0), kSyntheticFrames);
  EXPECT_EQ(geo.value("landmarks", 0), 8);
  EXPECT_EQ(geo.value("landmarks_associated", 0), 8);
  EXPECT_GE(geo.value("topology_turn_nodes", 0), 1);
  EXPECT_GE(geo.value("objects", 0), 10);
  const nlohmann::json& ge = j["geo_evaluation"];
  EXPECT_EQ(ge.value("landmarks", 0), 8);
  // Measured (seeds 1, 2, 3): median 3.86, 2.36, 1.73 m in 3-D and 1.33, 0.84, 0.68 m horizontally;
  // trajectory 1.61, 1.32, 0.77 m RMSE. The error is mostly the noise of the 7 GPS samples (1 m, every 30
  // frames).
  EXPECT_LE(ge["landmark_error_median_m"].get<double>(), 6.0);
  EXPECT_LE(ge["landmark_error_horizontal_median_m"].get<double>(), 3.0);
  const double geo_ate = ge["trajectory_ate_rmse_m"].get<double>();
  EXPECT_LE(geo_ate, 3.0);

  // trajectory_wgs84.csv against the true positions: one row per tracked frame; our RMSE is run.json's.
  const sim::SyntheticCity city(sim::ReadSceneOptions(data / "scene.json"));
  const std::vector<double> times = SequenceTimes(data);
  const std::vector<std::string> rows = Lines(ReadText(run / "trajectory_wgs84.csv"));
  ASSERT_GE(rows.size(), 2u);
  EXPECT_EQ(rows[0], "t,lat,lon,alt");
  double sum = 0.0;
  size_t n = 0;
  for (size_t i = 1; i < rows.size(); ++i) {
    double t, lat, lon, alt;
    char c1, c2, c3;
    std::istringstream in(rows[i]);
    ASSERT_TRUE(in >> t >> c1 >> lat >> c2 >> lon >> c3 >> alt) << rows[i];
    const int frame = FrameIndices({t}, times)[0];
    ASSERT_GE(frame, 0) << rows[i];
    const Eigen::Vector3d truth =
        city.EnuFromWorld() * city.WorldFromCamera(static_cast<size_t>(frame)).translation;
    const Eigen::Vector3d estimate = city.enu().ToEnu(Wgs84{lat, lon, alt});
    sum += (estimate - truth).squaredNorm();
    ++n;
  }
  EXPECT_EQ(static_cast<int>(n), ReadTumTrajectory(run / "trajectory.tum").size());
  EXPECT_NEAR(std::sqrt(sum / static_cast<double>(n)), geo_ate, 0.05);

  // landmarks.geojson: the catalogue's eight landmarks, at their catalogue coordinates.
  const nlohmann::json catalogue = ReadJson(data / "scene.json")["landmarks"];
  const nlohmann::json placed = ReadJson(run / "landmarks.geojson");
  ASSERT_EQ(placed.value("type", ""), "FeatureCollection");
  ASSERT_EQ(placed["features"].size(), catalogue.size());
  for (size_t i = 0; i < catalogue.size(); ++i) {
    const nlohmann::json& f = placed["features"][i];
    EXPECT_EQ(f["properties"]["name"], catalogue[i]["name"]);
    EXPECT_NEAR(f["geometry"]["coordinates"][0].get<double>(), catalogue[i]["longitude"].get<double>(), 1e-7);
    EXPECT_NEAR(f["geometry"]["coordinates"][1].get<double>(), catalogue[i]["latitude"].get<double>(), 1e-7);
  }
  // The topology: every landmark at a node; GraphML with as many nodes as topology.json; DOT an undirected
  // graph.
  const nlohmann::json topology = ReadJson(run / "topology.json");
  ASSERT_TRUE(topology.contains("nodes") && topology.contains("edges"));
  std::set<int> landmarks_at_nodes;
  for (const nlohmann::json& node : topology["nodes"]) {
    for (const nlohmann::json& l : node["landmarks"]) landmarks_at_nodes.insert(l.get<int>());
  }
  EXPECT_EQ(landmarks_at_nodes.size(), catalogue.size());
  EXPECT_EQ(topology["nodes"].size(), static_cast<size_t>(geo.value("topology_nodes", -1)));
  EXPECT_EQ(topology["edges"].size(), static_cast<size_t>(geo.value("topology_edges", -1)));
  const std::string graphml = ReadText(run / "topology.graphml");
  const auto count = [](const std::string& text, const std::string& what) {
    size_t k = 0;
    for (size_t pos = text.find(what); pos != std::string::npos; pos = text.find(what, pos + 1)) ++k;
    return k;
  };
  EXPECT_EQ(count(graphml, "<node "), topology["nodes"].size());
  EXPECT_EQ(count(graphml, "<edge "), topology["edges"].size());
  EXPECT_THAT(ReadText(run / "topology.dot"), StartsWith("graph"));
  const nlohmann::json topo_geo = ReadJson(run / "topology.geojson");
  EXPECT_EQ(topo_geo.value("type", ""), "FeatureCollection");
  const nlohmann::json objects = ReadJson(run / "objects.json");
  EXPECT_EQ(objects.value("num_objects", -1), static_cast<int>(objects["objects"].size()));
  EXPECT_EQ(objects.value("num_objects", -1), geo.value("objects", -2));
}

// `semslam route` between two landmarks of landmarks.csv: steps a person can follow, with the true length,
// the true side of each landmark passed and the true turn; an unknown name is a one-line error.
TEST_F(SyntheticRun, RoutesBetweenLandmarks) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, MonoRun());
  // Names from landmarks.csv (name,lat,lon,alt,category), in the order of the drive.
  const std::vector<std::string> csv = Lines(ReadText(data / "landmarks.csv"));
  ASSERT_GE(csv.size(), 3u);
  const auto name_of = [](const std::string& row) { return row.substr(0, row.find(',')); };
  const std::string from = name_of(csv[1]);
  const std::string to = name_of(csv.back());
  ASSERT_NE(from, to);

  const CommandResult r =
      RunSemslam({"route", "--map", (run / "map.semslam").string(), "--from", from, "--to", to});
  ASSERT_TRUE(r.Succeeded()) << r.Describe();
  const std::vector<std::string> lines = Lines(r.out);
  ASSERT_GE(lines.size(), 3u) << r.out;
  EXPECT_THAT(lines[0], StartsWith("Route from " + from + " to " + to + ", ")) << r.out;
  EXPECT_THAT(lines[1], HasSubstr("1. Start at " + from)) << r.out;
  EXPECT_THAT(lines.back(), HasSubstr("You have arrived at " + to)) << r.out;

  // The truth: the landmarks' nearest frames, their sides of the road, the turns in between.
  const nlohmann::json scene = ReadJson(data / "scene.json");
  const std::vector<Rigid3d> poses = ReadKittiPoses(data / "poses" / "00.txt");
  std::map<std::string, std::pair<int, std::string>> truth;  // name -> nearest frame, side
  for (const nlohmann::json& l : scene["landmarks"]) {
    const int frame = l["nearest_frame"].get<int>();
    const Eigen::Vector3d world(l["position"][0].get<double>(), l["position"][1].get<double>(),
                                l["position"][2].get<double>());
    const Eigen::Vector3d in_camera = poses[static_cast<size_t>(frame)].Inverse() * world;
    truth[l["name"].get<std::string>()] = {frame, in_camera.x() < 0 ? "left" : "right"};
  }
  ASSERT_TRUE(truth.count(from) && truth.count(to));
  const int from_frame = truth[from].first, to_frame = truth[to].first;
  const double true_length = ArcLengthTo(poses, to_frame) - ArcLengthTo(poses, from_frame);

  const std::regex pass(R"(Drive \d+ m to (.+) \(on your (left|right)\)\.)");
  int passed = 0;
  for (const std::string& line : lines) {
    std::smatch m;
    if (!std::regex_search(line, m, pass)) continue;
    ++passed;
    // Landmarks at one keyframe share a node: "A / B".
    const std::string names = m[1].str();
    for (size_t start = 0; start <= names.size();) {
      const size_t end = std::min(names.find(" / ", start), names.size());
      const std::string name = names.substr(start, end - start);
      ASSERT_TRUE(truth.count(name)) << line;
      EXPECT_EQ(m[2].str(), truth[name].second) << line;
      start = end + 3;
    }
  }
  EXPECT_GE(passed, 3) << r.out;
  std::set<std::string> true_turns, route_turns;
  for (const nlohmann::json& turn : scene["route"]["turns"]) {
    const int frame = turn["frame"].get<int>();
    if (frame > from_frame && frame < to_frame) true_turns.insert(turn["direction"].get<std::string>());
  }
  for (const std::string& line : lines) {
    if (line.find("Turn left") != std::string::npos) route_turns.insert("left");
    if (line.find("Turn right") != std::string::npos) route_turns.insert("right");
  }
  EXPECT_EQ(route_turns, true_turns) << r.out;

  const CommandResult json =
      RunSemslam({"route", "--json", "--map", (run / "map.semslam").string(), "--from", from, "--to", to});
  ASSERT_TRUE(json.Succeeded()) << json.Describe();
  const nlohmann::json route = nlohmann::json::parse(json.out, nullptr, false);
  ASSERT_TRUE(route.is_object()) << json.out;
  EXPECT_NEAR(route["length_m"].get<double>(), true_length, 0.05 * true_length);
  EXPECT_EQ(route["from"], from);
  EXPECT_EQ(route["to"], to);

  const CommandResult unknown =
      RunSemslam({"route", "--map", (run / "map.semslam").string(), "--from", from, "--to", "Nowhere Plaza"});
  EXPECT_FALSE(unknown.Crashed()) << unknown.Describe();
  EXPECT_NE(unknown.exit_code, 0) << unknown.Describe();
  EXPECT_EQ(Lines(unknown.err).size(), 1u) << unknown.err;
  EXPECT_THAT(unknown.err, HasSubstr("Nowhere Plaza"));
  EXPECT_TRUE(unknown.out.empty()) << unknown.out;
}

// Stereo: metric scale, so SE(3) alignment is enough and Sim(3) finds a scale of 1.
TEST_F(SyntheticRun, StereoIsMetric) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  SEMSLAM_ASSERT_ARTIFACT(run, StereoRun());
  const nlohmann::json j = ReadJson(run / "run.json");
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j.value("mode", ""), "stereo");
  EXPECT_EQ(j.value("frames", -1), kSyntheticFrames);
  EXPECT_EQ(j.value("tracked", -1), kSyntheticFrames);  // stereo initializes on the first frame
  EXPECT_EQ(j.value("ate_alignment", ""), "se3");
  EXPECT_LE(j["ate_rmse"].get<double>(), kStereoAteM);
  EXPECT_DOUBLE_EQ(j.value("ate_scale", 0.0), 1.0);
  EXPECT_TRUE(j.value("intrinsics_refinement", nlohmann::json{1}).empty());  // stereo keeps the calibration
  const Trajectory trajectory = ReadTumTrajectory(run / "trajectory.tum");
  EXPECT_EQ(trajectory.size(), static_cast<size_t>(kSyntheticFrames));

  const std::vector<std::string> common = {"eval",
                                           "--estimate",
                                           (run / "trajectory.tum").string(),
                                           "--truth",
                                           (data / "poses" / "00.txt").string(),
                                           "--times",
                                           (SequenceDir(data) / "times.txt").string()};
  std::vector<std::string> se3 = common;
  se3.insert(se3.end(), {"--align", "se3"});
  const CommandResult r_se3 = RunSemslam(se3);
  ASSERT_TRUE(r_se3.Succeeded()) << r_se3.Describe();
  const nlohmann::json e_se3 = nlohmann::json::parse(r_se3.out, nullptr, false);
  EXPECT_NEAR(e_se3["ate_rmse"].get<double>(), j["ate_rmse"].get<double>(), 1e-4);
  EXPECT_LE(e_se3["ate_rmse"].get<double>(), kStereoAteM);
  const CommandResult r_sim3 = RunSemslam(common);
  ASSERT_TRUE(r_sim3.Succeeded()) << r_sim3.Describe();
  const nlohmann::json e_sim3 = nlohmann::json::parse(r_sim3.out, nullptr, false);
  EXPECT_NEAR(e_sim3["scale"].get<double>(), 1.0, kStereoScaleTolerance);
  // Metric without alignment of the scale: the travelled distance is the true one.
  EXPECT_NEAR(PathLength(trajectory), e_sim3["path_length_m"].get<double>(),
              0.01 * e_sim3["path_length_m"].get<double>());

  // Without --gps and --landmarks there is nothing geographic to write; without a segmenter, no labels.
  for (const char* file : {"trajectory_wgs84.csv", "landmarks.geojson", "topology.json", "objects.json"}) {
    EXPECT_FALSE(fs::exists(run / file)) << file;
  }
  EXPECT_FALSE(j.contains("geo_evaluation"));
  EXPECT_EQ(j["classes"]["unlabeled"].get<long long>(), j["points"].get<long long>());
  for (const char* file : {"trajectory.tum", "keyframes.tum", "trajectory.kitti", "map.semslam",
                           "semantic_map.ply", "timing.json"}) {
    EXPECT_TRUE(fs::exists(run / file)) << file;
  }
}

// --pacing synchronous promises reproducible runs (slam_system.h): the same frames twice give the same bytes.
// A segmenter (asynchronous by design) may change labels but never the trajectory.
TEST_F(SyntheticRun, SynchronousPacingIsReproducible) {
  SEMSLAM_ASSERT_ARTIFACT(data, SyntheticDataset());
  testing::TempDir dir;
  const auto run = [&](const std::string& out, const std::string& segmenter) {
    return RunSemslam({"run", "--sequence", SequenceDir(data).string(), "--out", (dir / out).string(),
                       "--mode", "mono", "--frames", "0:40", "--pacing", "synchronous", "--segmenter",
                       segmenter, "-q"});
  };
  for (const auto& [out, segmenter] : {std::pair{"a", "none"}, {"b", "none"}, {"c", "truth-noisy:0.25"}}) {
    const CommandResult r = run(out, segmenter);
    ASSERT_TRUE(r.Succeeded()) << r.Describe();
  }
  EXPECT_GE(ReadJson(dir / "a" / "run.json").value("tracked", 0), 35);
  for (const char* file :
       {"trajectory.tum", "keyframes.tum", "trajectory.kitti", "map.semslam", "semantic_map.ply"}) {
    EXPECT_TRUE(SameBytes(dir / "a" / file, dir / "b" / file))
        << file << " differs between two identical runs";
  }
  for (const char* file : {"trajectory.tum", "keyframes.tum"}) {
    EXPECT_TRUE(SameBytes(dir / "a" / file, dir / "c" / file)) << file << " changes with segmentation";
  }
}

}  // namespace
}  // namespace semslam::system_test
