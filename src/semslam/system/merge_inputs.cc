#include "semslam/system/merge_inputs.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "semslam/core/error.h"
#include "semslam/io/sequence.h"
#include "semslam/sim/scene_file.h"
#include "semslam/system/run_metadata.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

std::optional<Eigen::Vector3d> LeverArmOf(const nlohmann::json& j) {
  if (!j.contains("gps_lever_arm") || j["gps_lever_arm"].is_null()) return std::nullopt;
  const auto v = j["gps_lever_arm"].get<std::vector<double>>();
  if (v.size() != 3)
    throw nlohmann::json::other_error::create(501, "gps_lever_arm: 3 numbers expected", nullptr);
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

double CameraHeightOf(const nlohmann::json& j) {
  const double height = j.value("camera_height_m", RoadScaleOptions{}.camera_height_m);
  if (!std::isfinite(height) || height <= 0)
    throw nlohmann::json::other_error::create(501, "camera_height_m: a positive number of metres expected",
                                              nullptr);
  return height;
}

}  // namespace

InputRun ReadInputRun(const fs::path& dir) {
  InputRun run;
  run.dir = fs::absolute(dir);
  if (!fs::is_regular_file(dir / "map.semslam"))
    throw InputError(dir / "map.semslam", "missing: not a run folder with a saved map");
  const fs::path json_path = dir / "run.json";
  const nlohmann::json j = ReadJsonFile(json_path);
  try {
    run.mode = j.at("mode").get<std::string>();
    if (run.mode != "mono" && run.mode != "stereo")
      throw InputError(json_path, "mode: expected mono or stereo");
    if (j.value("command", std::string("run")) == "merge") {
      for (const auto& c : j.value("landmark_catalogues", nlohmann::json::array()))
        run.catalogues.emplace_back(c.get<std::string>());
      for (const auto& s : j.at("maps").at("sessions")) {
        if (!s.contains("frames_csv")) continue;
        run.sessions[s.at("id").get<std::uint32_t>()] = {s.value("sequence", std::string()),
                                                         s.value("camera", std::string()),
                                                         run.dir / s.at("frames_csv").get<std::string>(),
                                                         s.value("gps", std::string()),
                                                         s.value("gps_every", 30),
                                                         LeverArmOf(s),
                                                         CameraHeightOf(s)};
      }
    } else {
      const std::string landmarks = j.at("config").value("landmarks", std::string());
      if (!landmarks.empty()) run.catalogues.emplace_back(landmarks);
      if (fs::is_regular_file(dir / "frames.csv")) {
        const nlohmann::json& config = j.at("config");
        // The sequence as the run was given it (run.json's own "sequence" is the folder of its images).
        run.sessions[kLastSession] = {config.value("sequence", j.at("sequence").get<std::string>()),
                                      j.value("camera", std::string()),
                                      run.dir / "frames.csv",
                                      config.value("gps", std::string()),
                                      config.value("gps_every", 30),
                                      LeverArmOf(config),
                                      CameraHeightOf(config)};
      }
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(json_path, fmt::format("not a run's run.json: {}", e.what()));
  }
  return run;
}

std::vector<Landmark> UnionOfCatalogues(const std::vector<fs::path>& paths) {
  std::vector<Landmark> out;
  std::set<fs::path> seen;
  for (const fs::path& path : paths) {
    if (!seen.insert(fs::absolute(path)).second) continue;
    for (Landmark& l : ReadLandmarks(path)) {
      const bool duplicate = std::any_of(out.begin(), out.end(), [&](const Landmark& o) {
        const double north = (o.position.latitude_deg - l.position.latitude_deg) * 111320.0;
        const double east = (o.position.longitude_deg - l.position.longitude_deg) * 111320.0 *
                            std::cos(l.position.latitude_deg * M_PI / 180.0);
        return o.name == l.name && std::hypot(north, east) < 1.0;
      });
      if (!duplicate) out.push_back(std::move(l));
    }
  }
  return out;
}

std::optional<SessionTruth> TruthOf(const InputSession& session, bool stereo) {
  try {
    SequenceOptions options;
    options.camera = session.camera;
    options.stereo = stereo;
    std::optional<Trajectory> truth = OpenSequence(session.sequence, options)->GroundTruth();
    if (!truth) return std::nullopt;
    SessionTruth out{std::move(*truth), std::nullopt, {}};
    if (const auto scene = sim::FindSceneJson(session.sequence)) {
      const SceneTruth town = ReadSceneTruth(scene->parent_path());
      for (StampedPose& p : out.world_from_camera)
        p.world_from_camera = town.enu_from_world * p.world_from_camera;
      out.enu = EnuFrame(town.origin);
      out.landmarks = town.landmarks;
    }
    return out;
  } catch (const std::exception& e) {
    spdlog::warn("no ground truth for {}: {}", session.sequence, e.what());
    return std::nullopt;
  }
}

}  // namespace semslam
