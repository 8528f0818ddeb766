#include "semslam/report/geo_evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "semslam/core/error.h"
#include "semslam/io/trajectory_io.h"

namespace semslam {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

class SceneReader {
 public:
  explicit SceneReader(fs::path file) : file_(std::move(file)) {}
  [[noreturn]] void Fail(const std::string& field, const std::string& message) const {
    throw InputError(SourceLocation{file_, 0}, field, message);
  }
  const json& Member(const json& j, const std::string& key, const std::string& path) const {
    const std::string field = path.empty() ? key : path + "." + key;
    if (!j.is_object() || !j.contains(key)) Fail(field, "missing");
    return j.at(key);
  }
  double Number(const json& j, const std::string& key, const std::string& path) const {
    const json& v = Member(j, key, path);
    if (!v.is_number() || !std::isfinite(v.get<double>())) Fail(path + "." + key, "expected a finite number");
    return v.get<double>();
  }
  int Integer(const json& j, const std::string& key, const std::string& path) const {
    const json& v = Member(j, key, path);
    if (!v.is_number_integer()) Fail(path + "." + key, "expected an integer");
    return v.get<int>();
  }
  Eigen::Vector3d Vector(const json& v, const std::string& field) const {
    if (!v.is_array() || v.size() != 3) Fail(field, "expected [x, y, z]");
    Eigen::Vector3d out;
    for (int i = 0; i < 3; ++i) {
      const json& c = v[static_cast<size_t>(i)];
      if (!c.is_number() || !std::isfinite(c.get<double>()))
        Fail(fmt::format("{}[{}]", field, i), "expected a number");
      out[i] = c.get<double>();
    }
    return out;
  }
  const json& Array(const json& j, const std::string& key, const std::string& path) const {
    const json& v = Member(j, key, path);
    if (!v.is_array()) Fail(path.empty() ? key : path + "." + key, "expected an array");
    return v;
  }

 private:
  fs::path file_;
};

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The landmark figures of e.landmark_errors.
void SummarizeLandmarkErrors(GeoEvaluation& e) {
  std::vector<double> errors, horizontal;
  for (const GeoEvaluation::LandmarkError& l : e.landmark_errors) {
    errors.push_back(l.error_m);
    horizontal.push_back(l.horizontal_m);
  }
  e.landmarks = static_cast<int>(errors.size());
  if (errors.empty()) return;
  e.landmark_error_median_m = Median(errors);
  e.landmark_error_max_m = *std::max_element(errors.begin(), errors.end());
  e.landmark_error_horizontal_median_m = Median(horizontal);
  e.landmark_error_horizontal_max_m = *std::max_element(horizontal.begin(), horizontal.end());
}

// The true pose at `timestamp` (within a millisecond) of a trajectory in time order, or null.
const Rigid3d* TruePoseAt(const Trajectory& truth, double timestamp) {
  const auto it = std::lower_bound(truth.begin(), truth.end(), timestamp - 1e-3,
                                   [](const StampedPose& p, double t) { return p.timestamp < t; });
  if (it == truth.end() || std::abs(it->timestamp - timestamp) > 1e-3) return nullptr;
  return &it->world_from_camera;
}

}  // namespace

void GeoEvaluationOptions::Check() const {
  Require(std::isfinite(scale_window_m) && scale_window_m > 0,
          "geo evaluation scale_window_m must be positive");
  Require(max_distance_m > 0, "geo evaluation max_distance_m must be positive");
}

SceneTruth ReadSceneTruth(const fs::path& dataset_dir, const std::string& sequence) {
  const fs::path file = dataset_dir / "scene.json";
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw InputError(file, "cannot open the scene file");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  json root;
  try {
    root = json::parse(buffer.str());
  } catch (const json::parse_error& e) {
    throw InputError(SourceLocation{file, 0}, "json", e.what());
  }
  const SceneReader r(file);
  SceneTruth truth;
  const json& origin = r.Member(root, "origin", "");
  truth.origin = Wgs84{r.Number(origin, "latitude", "origin"), r.Number(origin, "longitude", "origin"),
                       r.Number(origin, "altitude", "origin")};
  if (!truth.origin.IsValid()) r.Fail("origin", "not a valid WGS84 position");
  const json& t = r.Member(root, "enu_from_world", "");
  const json& rows = r.Array(t, "rotation", "enu_from_world");
  if (rows.size() != 3) r.Fail("enu_from_world.rotation", "expected 3 rows");
  Eigen::Matrix3d rotation;
  for (int i = 0; i < 3; ++i)
    rotation.row(i) = r.Vector(rows[static_cast<size_t>(i)], fmt::format("enu_from_world.rotation[{}]", i));
  truth.enu_from_world =
      Rigid3d(rotation, r.Vector(r.Member(t, "translation", "enu_from_world"), "enu_from_world.translation"));

  const json& route = r.Member(root, "route", "");
  const json& positions = r.Array(route, "positions", "route");
  for (size_t i = 0; i < positions.size(); ++i) {
    truth.positions_world.push_back(r.Vector(positions[i], fmt::format("route.positions[{}]", i)));
  }
  const json& turns = r.Array(route, "turns", "route");
  for (size_t i = 0; i < turns.size(); ++i) {
    const std::string p = fmt::format("route.turns[{}]", i);
    SceneTruth::Turn turn;
    turn.frame = r.Integer(turns[i], "frame", p);
    turn.world = r.Vector(r.Member(turns[i], "position", p), p + ".position");
    const json& direction = r.Member(turns[i], "direction", p);
    if (!direction.is_string() || (direction != "left" && direction != "right"))
      r.Fail(p + ".direction", "expected left or right");
    turn.left = direction == "left";
    turn.intersection = r.Integer(turns[i], "intersection", p);
    truth.turns.push_back(turn);
  }
  const json& revisits = r.Array(route, "revisits", "route");
  for (size_t i = 0; i < revisits.size(); ++i) {
    const std::string p = fmt::format("route.revisits[{}]", i);
    truth.revisits.push_back(
        {r.Integer(revisits[i], "frame", p), r.Integer(revisits[i], "earlier_frame", p)});
  }
  const json& graph = r.Member(root, "street_graph", "");
  const json& intersections = r.Array(graph, "intersections", "street_graph");
  for (size_t i = 0; i < intersections.size(); ++i) {
    const std::string p = fmt::format("street_graph.intersections[{}]", i);
    SceneTruth::Intersection node;
    node.id = r.Integer(intersections[i], "id", p);
    node.enu = r.Vector(r.Member(intersections[i], "enu", p), p + ".enu");
    const json& drivable = r.Member(intersections[i], "drivable", p);
    if (!drivable.is_boolean()) r.Fail(p + ".drivable", "expected true or false");
    node.drivable = drivable.get<bool>();
    truth.intersections.push_back(node);
  }
  const json& segments = r.Array(graph, "segments", "street_graph");
  for (size_t i = 0; i < segments.size(); ++i) {
    const std::string p = fmt::format("street_graph.segments[{}]", i);
    truth.segments.push_back({r.Integer(segments[i], "id", p), r.Integer(segments[i], "from", p),
                              r.Integer(segments[i], "to", p), r.Number(segments[i], "length", p),
                              r.Integer(segments[i], "driven", p)});
  }
  const json& landmarks = r.Array(root, "landmarks", "");
  for (size_t i = 0; i < landmarks.size(); ++i) {
    const std::string p = fmt::format("landmarks[{}]", i);
    SceneTruth::Landmark l;
    const json& name = r.Member(landmarks[i], "name", p);
    if (!name.is_string()) r.Fail(p + ".name", "expected a string");
    l.name = name.get<std::string>();
    if (landmarks[i].contains("category") && landmarks[i]["category"].is_string())
      l.category = landmarks[i]["category"];
    l.enu = r.Vector(r.Member(landmarks[i], "enu", p), p + ".enu");
    l.nearest_frame = r.Integer(landmarks[i], "nearest_frame", p);
    truth.landmarks.push_back(std::move(l));
  }
  const fs::path poses = dataset_dir / "poses" / (sequence + ".txt");
  if (fs::exists(poses)) truth.world_from_camera = ReadKittiPoses(poses);
  return truth;
}

std::string GeoEvaluation::ToJson() const {
  json errors = json::array();
  for (const LandmarkError& e : landmark_errors) {
    errors.push_back({{"name", e.name}, {"error_m", e.error_m}, {"horizontal_m", e.horizontal_m}});
  }
  const json j = {{"trajectory_frames", trajectory_frames},
                  {"trajectory_ate_rmse_m", trajectory_ate_rmse_m},
                  {"trajectory_ate_max_m", trajectory_ate_max_m},
                  {"landmarks", landmarks},
                  {"landmarks_too_far", landmarks_too_far},
                  {"landmark_error_median_m", landmark_error_median_m},
                  {"landmark_error_max_m", landmark_error_max_m},
                  {"landmark_error_horizontal_median_m", landmark_error_horizontal_median_m},
                  {"landmark_error_horizontal_max_m", landmark_error_horizontal_max_m},
                  {"landmark_errors", errors}};
  return j.dump();
}

GeoEvaluation EvaluateGeo(const GeoOutputs& outputs, const GeoInputs& inputs, const SceneTruth& truth,
                          const GeoEvaluationOptions& options) {
  options.Check();
  Require(outputs.georeference.has_value(), "geo evaluation needs a georeference (GPS)");
  const Georeference& g = *outputs.georeference;
  const EnuFrame scene_enu(truth.origin);
  GeoEvaluation e;

  // The WGS84 trajectory.
  const std::vector<FramePose>& frames = inputs.frames.empty() ? inputs.keyframes : inputs.frames;
  double sum = 0.0;
  for (const FramePose& f : frames) {
    if (f.frame_index >= truth.positions_world.size()) continue;
    const Wgs84 estimate = g.enu_frame.ToWgs84(g.FrameToEnu(f.frame_index, f.world_from_camera.translation));
    const double error = (scene_enu.ToEnu(estimate) - truth.TrueEnu(f.frame_index)).norm();
    sum += error * error;
    e.trajectory_ate_max_m = std::max(e.trajectory_ate_max_m, error);
    ++e.trajectory_frames;
  }
  if (e.trajectory_frames > 0) e.trajectory_ate_rmse_m = std::sqrt(sum / e.trajectory_frames);

  // Landmarks, through their nearest keyframe's true pose and the local scale.
  if (truth.world_from_camera.empty()) return e;
  const std::vector<FramePose>& keyframes = inputs.keyframes;
  std::vector<double> true_arc(keyframes.size(), 0.0), est_arc(keyframes.size(), 0.0);
  for (size_t k = 1; k < keyframes.size(); ++k) {
    const size_t a = keyframes[k - 1].frame_index, b = keyframes[k].frame_index;
    if (b >= truth.positions_world.size()) break;
    true_arc[k] = true_arc[k - 1] + (truth.positions_world[b] - truth.positions_world[a]).norm();
    est_arc[k] =
        est_arc[k - 1] +
        (keyframes[k].world_from_camera.translation - keyframes[k - 1].world_from_camera.translation).norm();
  }
  std::map<std::string, const SceneTruth::Landmark*> by_name;
  for (const SceneTruth::Landmark& l : truth.landmarks) by_name[l.name] = &l;
  for (const PlacedLandmark& placed : outputs.landmarks) {
    const auto it = by_name.find(placed.landmark.name);
    if (it == by_name.end() || placed.nearest_keyframe < 0) continue;
    if (placed.keyframe_distance_m > options.max_distance_m) {
      ++e.landmarks_too_far;
      continue;
    }
    const size_t k = static_cast<size_t>(placed.nearest_keyframe);
    const size_t frame = keyframes.at(k).frame_index;
    if (frame >= truth.world_from_camera.size()) continue;
    // Local scale: true over estimated path length within the window around the keyframe.
    size_t lo = k, hi = k;
    while (lo > 0 && true_arc[k] - true_arc[lo - 1] <= options.scale_window_m) --lo;
    while (hi + 1 < keyframes.size() && true_arc[hi + 1] - true_arc[k] <= options.scale_window_m) ++hi;
    if (hi == lo || est_arc[hi] - est_arc[lo] <= 0) continue;
    const double metres_per_unit = (true_arc[hi] - true_arc[lo]) / (est_arc[hi] - est_arc[lo]);
    const Eigen::Vector3d in_camera = keyframes[k].world_from_camera.Inverse() * placed.map_position;
    const Eigen::Vector3d true_place =
        truth.enu_from_world * (truth.world_from_camera[frame] * (metres_per_unit * in_camera));
    const Eigen::Vector3d d = true_place - it->second->enu;
    e.landmark_errors.push_back({placed.landmark.name, d.norm(), d.head<2>().norm()});
  }
  SummarizeLandmarkErrors(e);
  return e;
}

GeoEvaluation EvaluateLandmarksAcrossDrives(const std::vector<PlacedLandmark>& placed,
                                            const std::vector<FramePose>& keyframes,
                                            const std::map<std::uint32_t, Trajectory>& truths,
                                            const Sim3d& town_from_map,
                                            const std::vector<SceneTruth::Landmark>& truth_landmarks) {
  std::map<std::string, const SceneTruth::Landmark*> by_name;
  for (const SceneTruth::Landmark& l : truth_landmarks) by_name[l.name] = &l;
  GeoEvaluation e;
  for (const PlacedLandmark& p : placed) {
    const auto truth_landmark = by_name.find(p.landmark.name);
    if (truth_landmark == by_name.end() || p.nearest_keyframe < 0) continue;
    const FramePose& kf = keyframes.at(static_cast<size_t>(p.nearest_keyframe));
    const auto truth = truths.find(kf.segment);
    if (truth == truths.end()) continue;
    const Rigid3d* town_from_camera = TruePoseAt(truth->second, kf.timestamp);
    if (town_from_camera == nullptr) continue;
    // The merged map is metric in the world: the landmark in its keyframe's camera, in metres.
    const Eigen::Vector3d in_camera = town_from_map.scale * (kf.world_from_camera.Inverse() * p.map_position);
    const Eigen::Vector3d d = *town_from_camera * in_camera - truth_landmark->second->enu;
    e.landmark_errors.push_back({p.landmark.name, d.norm(), d.head<2>().norm()});
  }
  SummarizeLandmarkErrors(e);
  return e;
}

}  // namespace semslam
