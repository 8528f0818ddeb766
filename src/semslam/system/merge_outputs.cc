#include "semslam/system/merge_outputs.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cctype>
#include <map>
#include <set>
#include <string>

#include "semslam/core/atomic_file.h"
#include "semslam/eval/trajectory_metrics.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/report/geo_evaluation.h"
#include "semslam/system/atlas_outputs.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

std::string SessionFolderName(const MapSession& s) {
  std::string name = s.name.empty() ? std::string("session") : s.name;
  for (char& c : name) {
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_' && c != '.') c = '_';
  }
  return fmt::format("{:03d}-{}", s.id, name);
}

Trajectory ToTrajectory(const std::vector<FramePose>& frames, std::uint32_t map_id) {
  Trajectory t;
  for (const FramePose& f : frames) {
    if (f.map_id == map_id && !f.predicted) t.push_back({f.timestamp, f.world_from_camera});
  }
  return t;
}

// The drives against their truth, gathered for one alignment of the whole city: each drive shifted in time
// past the others.
struct CityTruth {
  Trajectory estimate, truth;
  std::vector<std::pair<size_t, Trajectory>> drives;  // the session's index, its trajectory
  std::vector<Trajectory> drive_truths;
  // The synthetic town's truth in its ENU frame, by drive (FramePose::segment), for the landmarks.
  std::map<std::uint32_t, Trajectory> town_truths;
  std::optional<EnuFrame> town_enu;
  std::map<std::string, SceneTruth::Landmark> town_landmarks;  // by name: each drive's scene names its own
};

// Session k's ATE against its truth (alone, and in the world without alignment), gathered into `city`.
void EvaluateSession(const SessionTruth& truth, const Trajectory& trajectory, size_t k,
                     const std::optional<Georeference>& georeference, Alignment alignment, nlohmann::json& j,
                     CityTruth& city) {
  const AteResult ate = ComputeAte(trajectory, truth.world_from_camera, alignment);
  j["ate_rmse"] = ate.rmse;
  j["ate_matched"] = ate.matched;
  const double shift = 1e6 * static_cast<double>(city.drives.size() + 1);
  for (StampedPose p : trajectory) city.estimate.push_back({p.timestamp + shift, p.world_from_camera});
  for (StampedPose p : truth.world_from_camera)
    city.truth.push_back({p.timestamp + shift, p.world_from_camera});
  city.drives.emplace_back(k, trajectory);
  city.drive_truths.push_back(truth.world_from_camera);
  if (truth.enu) {
    city.town_truths[static_cast<std::uint32_t>(k)] = truth.world_from_camera;
    city.town_enu = truth.enu;
    for (const SceneTruth::Landmark& l : truth.landmarks) city.town_landmarks.emplace(l.name, l);
  }
  if (georeference && truth.enu) {
    // Where the merged map puts the drive in the world, against where it was: no alignment.
    Trajectory in_town = trajectory;
    for (StampedPose& p : in_town) {
      p.world_from_camera.translation =
          truth.enu->ToEnu(georeference->MapToWgs84(p.world_from_camera.translation));
    }
    j["world_rmse_m"] = ComputeAte(in_town, truth.world_from_camera, Alignment::kNone).rmse;
  }
}

// One session's folder and run.json entry; its frames (and keyframes) in the main map join the city's
// geographic inputs.
nlohmann::json WriteSession(const Map& map, SessionRecord& s, size_t k, const MergeOutputOptions& options,
                            const std::optional<Georeference>& georeference, CityTruth& city,
                            GeoInputs& geo) {
  const std::uint32_t main_map = options.main_map;
  const MapSession& info = map.sessions()[s.id];
  const fs::path folder = fs::path("sessions") / SessionFolderName(info);
  fs::create_directories(options.folder / folder);
  nlohmann::json j = {{"id", s.id}, {"name", info.name}, {"source", info.source}, {"run", s.run.string()}};
  const std::vector<FramePose> keyframes = SessionKeyFrames(s);
  size_t unanchored = 0;
  s.frames = SessionFrames(s, options.frame_scale, &unanchored);
  std::map<std::uint32_t, size_t> frames_per_map;
  for (const FramePose& f : s.frames) ++frames_per_map[f.map_id];
  const size_t in_main = frames_per_map.count(main_map) ? frames_per_map.at(main_map) : 0;
  j["frames"] = s.frames.size();
  j["frames_in_main_map"] = in_main;
  j["frames_without_keyframe"] = unanchored;
  j["keyframes"] = keyframes.size();
  j["in_main_map"] = in_main > 0 && in_main == s.frames.size();
  nlohmann::json per_map = nlohmann::json::object();
  for (const auto& [id, n] : frames_per_map) per_map[std::to_string(id)] = n;
  j["frames_per_map"] = per_map;
  if (s.input) {
    j["sequence"] = s.input->sequence;
    j["camera"] = s.input->camera;
    j["gps"] = s.input->gps;
    j["gps_every"] = s.input->gps_every;
    if (s.input->lever_arm) {
      j["gps_lever_arm"] = {s.input->lever_arm->x(), s.input->lever_arm->y(), s.input->lever_arm->z()};
    }
    j["camera_height_m"] = s.input->camera_height_m;
  }
  const Trajectory trajectory = ToTrajectory(s.frames, main_map);
  WriteTumTrajectory(options.folder / folder / "trajectory.tum", trajectory);
  WriteTumTrajectory(options.folder / folder / "keyframes.tum", ToTrajectory(keyframes, main_map));
  WriteFramesCsv(options.folder / folder / "frames.csv", s.frames, main_map);
  j["trajectory"] = (folder / "trajectory.tum").string();
  j["frames_csv"] = (folder / "frames.csv").string();
  if (georeference && in_main > 0) {
    std::string text = "t,lat,lon,alt\n";
    for (const StampedPose& p : trajectory) {
      const Wgs84 w = georeference->MapToWgs84(p.world_from_camera.translation);
      text += fmt::format("{:.6f},{:.9f},{:.9f},{:.3f}\n", p.timestamp, w.latitude_deg, w.longitude_deg,
                          w.altitude_m);
    }
    WriteFileAtomically(options.folder / folder / "trajectory_wgs84.csv", text);
    j["trajectory_wgs84"] = (folder / "trajectory_wgs84.csv").string();
  }
  if (s.input && trajectory.size() >= 3) {
    if (const std::optional<SessionTruth> truth = TruthOf(*s.input, options.stereo)) {
      try {
        EvaluateSession(*truth, trajectory, k, georeference,
                        options.stereo ? Alignment::kSe3 : Alignment::kSim3, j, city);
      } catch (const EvaluationError& e) {
        spdlog::warn("session {}: no ATE: {}", s.id, e.what());
      }
    }
  }
  // The city's frames for the geographic outputs: the drives one after another, in frame-index ranges of
  // their own.
  if (in_main > 0) {
    const size_t offset = k * 10'000'000;
    for (FramePose f : s.frames) {
      if (f.map_id != main_map || f.predicted) continue;
      f.frame_index += offset;
      f.segment = static_cast<std::uint32_t>(k);
      geo.frames.push_back(f);
    }
    for (FramePose f : keyframes) {
      if (f.map_id != main_map) continue;
      f.frame_index += offset;
      f.segment = static_cast<std::uint32_t>(k);
      geo.keyframes.push_back(f);
    }
  }
  return j;
}

// One alignment of every drive's trajectory together: how far each lies from the others in the merged map.
std::optional<double> CityAte(const CityTruth& city, Alignment alignment, nlohmann::json& sessions) {
  if (city.drives.empty()) return std::nullopt;
  try {
    const AteResult ate = ComputeAte(city.estimate, city.truth, alignment);
    for (size_t i = 0; i < city.drives.size(); ++i) {
      Trajectory aligned = city.drives[i].second;
      for (StampedPose& p : aligned)
        p.world_from_camera = ate.truth_from_estimate.TransformPose(p.world_from_camera);
      sessions[city.drives[i].first]["ate_rmse_city"] =
          ComputeAte(aligned, city.drive_truths[i], Alignment::kNone).rmse;
    }
    return ate.rmse;
  } catch (const EvaluationError& e) {
    spdlog::warn("no city ATE: {}", e.what());
    return std::nullopt;
  }
}

// How the objects of a monocular map without GPS get their scale: from the camera's height above the road the
// drives' runs were given, when they agree. Cameras at different heights would need a height per keyframe;
// the objects then stay in map units.
std::optional<RoadScaleOptions> RoadScaleOfDrives(const std::vector<SessionRecord>& sessions,
                                                  std::uint32_t map_id) {
  std::set<double> heights;
  for (const SessionRecord& s : sessions) {
    const bool in_map =
        std::any_of(s.frames.begin(), s.frames.end(), [&](const FramePose& f) { return f.map_id == map_id; });
    if (s.input && in_map) heights.insert(s.input->camera_height_m);
  }
  RoadScaleOptions options;
  if (heights.size() <= 1) {
    if (!heights.empty()) options.camera_height_m = *heights.begin();
    return options;
  }
  spdlog::warn(
      "objects: the drives' cameras rode at different heights above the road ({:.2f} to {:.2f} m): "
      "object radii and sizes are in map units, not metres",
      *heights.begin(), *heights.rbegin());
  return std::nullopt;
}

}  // namespace

MergeOutputs WriteMergeOutputs(const Map& map, std::vector<SessionRecord>& sessions,
                               const MergeOutputOptions& options) {
  const std::optional<Georeference> georeference =
      options.world ? std::optional<Georeference>(Georeference(*options.world, Sim3d())) : std::nullopt;
  MergeOutputs out;
  GeoInputs geo;
  CityTruth city;
  {
    auto lock = map.ReadLock();
    for (size_t k = 0; k < sessions.size(); ++k) {
      out.sessions.push_back(WriteSession(map, sessions[k], k, options, georeference, city, geo));
    }
  }
  out.city_ate = CityAte(city, options.stereo ? Alignment::kSe3 : Alignment::kSim3, out.sessions);

  // Semantic map, landmarks, topology, objects, plots.
  out.semantic_points = SemanticPoints(map);
  WriteSemanticPly(options.folder / "semantic_map.ply", out.semantic_points);
  geo.map_id = options.main_map;
  geo.monocular = !options.stereo;
  {
    auto lock = map.ReadLock();
    for (const MapPoint* p : map.MapPointsOfMap(options.main_map)) {
      const SemanticPoint sp = ToSemanticPoint(p->position(), p->labels());
      if (IsValidTrainId(sp.label)) geo.points.push_back({sp.position, sp.label, sp.confidence});
    }
  }
  if (georeference && !geo.frames.empty()) {
    GeoInputs::Placed placed{*georeference};
    for (const FramePose& f : geo.frames)
      placed.single_similarity_enu.push_back(f.world_from_camera.translation);
    geo.placed = std::move(placed);
    if (!options.catalogues.empty()) geo.landmarks = UnionOfCatalogues(options.catalogues);
  }
  GeoOptions geo_options;
  if (geo.monocular && !georeference) geo_options.road_scale = RoadScaleOfDrives(sessions, options.main_map);
  out.geo = WriteGeoOutputs(geo, options.folder, geo_options);
  if (georeference && city.town_enu && !out.geo.landmarks.empty()) {
    std::vector<SceneTruth::Landmark> truth_landmarks;
    for (const auto& [name, landmark] : city.town_landmarks) truth_landmarks.push_back(landmark);
    const nlohmann::json e = nlohmann::json::parse(
        EvaluateLandmarksAcrossDrives(out.geo.landmarks, geo.keyframes, city.town_truths,
                                      EnuFromEnu(*city.town_enu, *options.world), truth_landmarks)
            .ToJson());
    if (e["landmarks"].get<int>() > 0) {
      out.landmark_evaluation = nlohmann::json::object();
      for (const char* key :
           {"landmarks", "landmark_error_median_m", "landmark_error_max_m",
            "landmark_error_horizontal_median_m", "landmark_error_horizontal_max_m", "landmark_errors"})
        out.landmark_evaluation[key] = e[key];
    }
  }
  return out;
}

}  // namespace semslam
