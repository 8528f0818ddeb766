#include "semslam/system/localizer.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <nlohmann/json.hpp>
#include <sstream>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/progress.h"
#include "semslam/eval/trajectory_metrics.h"
#include "semslam/geo/gps.h"
#include "semslam/geo/gps_alignment.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/report/geo_evaluation.h"
#include "semslam/report/geo_outputs.h"
#include "semslam/sim/scene_file.h"
#include "semslam/system/frame_reader.h"
#include "semslam/system/run_input_checks.h"
#include "semslam/system/run_output_dir.h"
#include "semslam/system/sequence_runner.h"

namespace semslam {
namespace {

struct LocalizedFrame {
  size_t frame = 0;
  double timestamp = 0.0;
  bool relocalized = false;
  std::uint32_t map_id = 0;
  Rigid3d world_from_camera;
  std::optional<GeoPose> geo;
};

std::string CsvLine(const LocalizedFrame& f, size_t max_landmarks) {
  const Eigen::Vector3d& t = f.world_from_camera.translation;
  const Eigen::Quaterniond& q = f.world_from_camera.rotation;
  std::string line = fmt::format("{},{:.6f},{},{},{:.6f},{:.6f},{:.6f},{:.9f},{:.9f},{:.9f},{:.9f}", f.frame,
                                 f.timestamp, f.relocalized ? "relocalized" : "tracked", f.map_id, t.x(),
                                 t.y(), t.z(), q.x(), q.y(), q.z(), q.w());
  if (f.geo) {
    line += fmt::format(",{:.9f},{:.9f},{:.3f},{:.1f}", f.geo->wgs84.latitude_deg, f.geo->wgs84.longitude_deg,
                        f.geo->wgs84.altitude_m, f.geo->heading_deg);
  } else {
    line += ",,,,";
  }
  for (size_t k = 0; k < max_landmarks; ++k) {
    if (f.geo && k < f.geo->nearest.size()) {
      const NamedMembership& m = f.geo->nearest[k];
      std::string name = m.name;
      for (char& c : name) c = c == ',' || c == '"' ? ' ' : c;
      line += fmt::format(",{},{:.1f},{:.4f}", name, m.distance_m, m.membership.value);
    } else {
      line += ",,,";
    }
  }
  return line + "\n";
}

// The name of the landmark nearest (horizontally) to an ENU position; empty when there is none.
std::string NearestTrueLandmark(const SceneTruth& truth, const Eigen::Vector3d& enu) {
  std::string best;
  double best_distance = std::numeric_limits<double>::infinity();
  for (const auto& landmark : truth.landmarks) {
    const double d = (landmark.enu.head<2>() - enu.head<2>()).norm();
    if (d < best_distance) {
      best_distance = d;
      best = landmark.name;
    }
  }
  return best;
}

// A georeference of the session's own, from its GPS, for each map the map file does not place in the world:
// the robust similarity (SE(3) for a metric stereo map) of the frames localized in it onto their fixes.
std::map<std::uint32_t, Georeference> SessionGeoreferences(const std::vector<LocalizedFrame>& localized,
                                                           const GeoContext& file, const GpsLog& log,
                                                           bool stereo, int every_n_frames) {
  std::map<std::uint32_t, Georeference> out;
  std::map<std::uint32_t, std::vector<FramePosition>> frames;
  std::vector<double> times;
  for (const LocalizedFrame& f : localized) {
    times.push_back(f.timestamp);
    if (file.Of(f.map_id) == nullptr) {
      frames[f.map_id].push_back({f.frame, -1, f.timestamp, f.world_from_camera.translation, 0,
                                  f.world_from_camera.rotation * Eigen::Vector3d::UnitY()});
    }
  }
  const EnuFrame enu = file.maps.empty() ? MakeEnuFrame(log) : file.maps.begin()->second.enu_frame;
  GpsSamplingOptions sampling;
  sampling.every_n_frames = every_n_frames;
  sampling.time_offset_s = GuessTimeOffset(log.fixes, times);
  GpsAlignmentOptions alignment;
  alignment.estimate_scale = !stereo;
  for (const auto& [map_id, positions] : frames) {
    const std::vector<GpsSample> samples = SampleGpsPairs(positions, log.fixes, enu, sampling);
    if (const auto fit = AlignMapToGps(samples, alignment)) {
      spdlog::info("map {} is placed in the world by this session's GPS: {} of {} fixes, {:.2f} m RMSE",
                   map_id, fit->num_inliers, samples.size(), fit->inlier_rmse_m);
      out.emplace(map_id, Georeference(enu, fit->enu_from_map));
    } else {
      spdlog::warn("map {}: this session's {} fixes on it do not place it in the world", map_id,
                   samples.size());
    }
  }
  return out;
}

// Frames first..end-1 tracked against the map, one after another: those with a pose. Stops at a signal or at
// too many bad frames in a row; `frames_run` counts the frames read.
std::vector<LocalizedFrame> LocalizeFrames(SlamSystem& slam, const ImageSequence& sequence, size_t first,
                                           size_t end, FrameReader& reader, ProgressReporter& progress,
                                           size_t* frames_run) {
  std::vector<LocalizedFrame> localized;
  for (size_t i = first; i < end && !InterruptRequested() && !reader.TooManyInRow(); ++i) {
    ++*frames_run;
    const std::optional<FrameImages> images = reader.Read(i);
    if (!images) continue;
    const TrackingResult result = slam.ProcessFrame(i, sequence.Timestamp(i), images->left, images->right);
    if (result.state == TrackingState::kOk && result.camera_from_world) {
      LocalizedFrame f;
      f.frame = i;
      f.timestamp = sequence.Timestamp(i);
      f.relocalized = result.relocalized;
      f.map_id = result.map_id;
      f.world_from_camera = result.camera_from_world->Inverse();
      localized.push_back(std::move(f));
    }
    progress.Update(i - first + 1, fmt::format("{} localized", localized.size()));
  }
  return localized;
}

// The camera tracking used: the map's, or the sequence's, and why.
nlohmann::json TrackingCameraJson(const TrackingCameraChoice& camera) {
  const PinholeCamera& c = camera.camera;
  return {{"source", camera.map_id ? "map" : "sequence"},
          {"map", camera.map_id ? nlohmann::json(*camera.map_id) : nlohmann::json()},
          {"reason", camera.reason},
          {"fx", c.fx},
          {"fy", c.fy},
          {"cx", c.cx},
          {"cy", c.cy},
          {"k1", c.distortion.k1},
          {"k2", c.distortion.k2}};
}

// Errors against the truth of a synthetic-city sequence: in the world (the scene's ENU frame, no alignment)
// and the nearest landmark when poses are in the world, else after one alignment of the trajectory.
void AddErrorsAgainstTheScene(const ImageSequence& sequence, const std::vector<LocalizedFrame>& localized,
                              const Trajectory& trajectory, bool stereo, LocalizeSummary& summary,
                              nlohmann::json& report) {
  const auto scene = sim::FindSceneJson(sequence.directory());
  if (!scene || localized.empty()) return;
  const SceneTruth truth = ReadSceneTruth(scene->parent_path());
  std::vector<double> errors;
  size_t landmark_checked = 0, landmark_right = 0;
  if (summary.in_world > 0) {
    // In the scene's ENU frame, without any alignment: the map's georeference against the drive's truth.
    const EnuFrame scene_enu(truth.origin);
    for (const LocalizedFrame& f : localized) {
      if (f.frame >= truth.positions_world.size() || !f.geo) continue;
      const Eigen::Vector3d true_enu = truth.TrueEnu(f.frame);
      errors.push_back((scene_enu.ToEnu(f.geo->wgs84) - true_enu).norm());
      if (!f.geo->nearest.empty() && !truth.landmarks.empty()) {
        ++landmark_checked;
        landmark_right += f.geo->nearest.front().name == NearestTrueLandmark(truth, true_enu) ? 1 : 0;
      }
    }
    report["error_frame"] = "enu";
  } else if (const auto ground_truth = sequence.GroundTruth(); ground_truth && localized.size() >= 3) {
    const AteResult ate = ComputeAte(trajectory, *ground_truth, stereo ? Alignment::kSe3 : Alignment::kSim3);
    errors = ate.errors;
    report["error_frame"] = stereo ? "se3-aligned" : "sim3-aligned";
  }
  if (!errors.empty()) {
    const auto within =
        static_cast<double>(std::count_if(errors.begin(), errors.end(), [](double e) { return e < 1.0; }));
    summary.within_1m = within / static_cast<double>(summary.frames);
    std::vector<double> sorted = errors;
    std::sort(sorted.begin(), sorted.end());
    report["within_1m"] = summary.within_1m;
    report["error_median_m"] = sorted[sorted.size() / 2];
    report["error_p95_m"] = sorted[std::min(sorted.size() - 1, sorted.size() * 95 / 100)];
    report["error_max_m"] = sorted.back();
  }
  if (landmark_checked > 0) {
    summary.nearest_landmark_right =
        static_cast<double>(landmark_right) / static_cast<double>(landmark_checked);
    report["nearest_landmark_right"] = summary.nearest_landmark_right;
  }
}

}  // namespace

void LocalizeOptions::Check() const {
  Require(!map.empty(), "localize: --map is required");
  Require(!sequence.empty(), "localize: --sequence is required");
  Require(!output.empty(), "localize: --out is required");
  Require(first_frame < end_frame, "localize: the frame range is empty");
  Require(max_landmarks >= 1, "localize: max_landmarks must be >= 1");
  Require(gps_every >= 1, "localize: --gps-every must be at least 1 frame");
}

LocalizeSummary LocalizeSequence(const LocalizeOptions& options) {
  options.Check();
  Stopwatch watch;
  SlamOptions slam_options = options.slam;
  slam_options.localization_only = true;
  const bool stereo = slam_options.mode == SensorMode::kStereo;
  const std::unique_ptr<ImageSequence> sequence = OpenSequence(options.sequence, {options.camera, stereo});
  const size_t first = options.first_frame;
  const size_t end = CheckFrameRange(*sequence, first, options.end_frame, stereo, "localize");
  OutputDirOptions output_dir_options;
  output_dir_options.overwrite = options.overwrite;
  output_dir_options.command = "localize";
  output_dir_options.inputs = {options.map, options.sequence, options.gps};
  const RunOutputDir output_dir(options.output, output_dir_options);
  SlamSystem slam(slam_options, sequence->camera(), sequence->stereo());
  const MapFileContents contents = slam.LoadMap(options.map);
  GeoContext geo;
  if (const auto it = contents.extra_sections.find("geo"); it != contents.extra_sections.end()) {
    auto lock = slam.map().ReadLock();
    // A version-1 section placed the file's one map: today's largest.
    geo = ParseGeoSection(it->second, std::filesystem::path(options.map.string() + "#geo"),
                          slam.map().MapWithMostKeyFrames());
  }
  std::optional<GpsLog> gps;
  if (!options.gps.empty()) {
    gps = ReadGps(options.gps);
    TimeFixesByFrame(*gps, FrameTimestamps(*sequence, 0, sequence->size()));
    LogSkippedFixes(*gps);
    CheckGpsLog(*gps, FrameTimestamps(*sequence, first, end));
  } else if (geo.maps.empty()) {
    spdlog::warn(
        "{} has no georeference (it was built without GPS) and no --gps was given: poses are reported in "
        "the map frame only",
        options.map.string());
  }

  ProgressReporter progress("localize", end - first, options.show_progress);
  FrameReader frame_reader(*sequence, stereo, options.max_bad_frames_in_row);
  size_t frames_run = 0;
  std::vector<LocalizedFrame> localized =
      LocalizeFrames(slam, *sequence, first, end, frame_reader, progress, &frames_run);
  slam.Finish();
  const SlamStatistics stats = slam.Statistics();
  progress.Finish(fmt::format("{} of {} frames localized, {} relocalizations", localized.size(), end - first,
                              stats.relocalizations));

  // In the world only through a georeference of the map each pose is in: the map file's, or this session's
  // GPS.
  std::map<std::uint32_t, Georeference> session;
  if (gps && !gps->fixes.empty())
    session = SessionGeoreferences(localized, geo, *gps, stereo, options.gps_every);
  std::map<std::uint32_t, size_t> per_map, per_map_in_world;
  for (LocalizedFrame& f : localized) {
    ++per_map[f.map_id];
    const Georeference* g = geo.Of(f.map_id);
    if (g == nullptr) {
      const auto it = session.find(f.map_id);
      g = it == session.end() ? nullptr : &it->second;
    }
    if (g == nullptr) continue;
    f.geo = LocateInWorld(f.world_from_camera, *g, geo,
                          f.map_id == geo.landmarks_map && !geo.landmarks.empty(), options.max_landmarks);
    ++per_map_in_world[f.map_id];
  }

  LocalizeSummary summary;
  summary.frames = frames_run;  // fewer than asked for when interrupted or stopped by bad frames
  summary.localized = localized.size();
  summary.relocalizations = stats.relocalizations;
  for (const auto& [map_id, n] : per_map_in_world) summary.in_world += n;

  Trajectory trajectory;
  std::string csv = "frame,t,status,map,x,y,z,qx,qy,qz,qw,lat,lon,alt,heading_deg";
  for (size_t k = 1; k <= options.max_landmarks; ++k)
    csv += fmt::format(",landmark{0},distance{0}_m,membership{0}", k);
  csv += "\n";
  for (const LocalizedFrame& f : localized) {
    trajectory.push_back({f.timestamp, f.world_from_camera});
    csv += CsvLine(f, options.max_landmarks);
  }
  WriteTumTrajectory(options.output / "trajectory.tum", trajectory);
  WriteFileAtomically(options.output / "localization.csv", csv);

  nlohmann::json maps = nlohmann::json::array();
  for (const auto& [map_id, n] : per_map) {
    const char* world = geo.Of(map_id) != nullptr   ? "map file"
                        : session.count(map_id) > 0 ? "this session's GPS"
                                                    : "none";
    maps.push_back(
        {{"map", map_id}, {"localized", n}, {"in_world", per_map_in_world[map_id]}, {"georeference", world}});
  }
  nlohmann::json report = {{"map", options.map.string()},
                           {"sequence", sequence->directory().string()},
                           {"mode", stereo ? "stereo" : "mono"},
                           {"frames", summary.frames},
                           {"localized", summary.localized},
                           {"relocalizations", summary.relocalizations},
                           {"in_world", summary.in_world},
                           {"georeferenced", !geo.maps.empty()},
                           {"maps", maps}};
  report["camera"] = TrackingCameraJson(slam.tracking_camera());
  AddErrorsAgainstTheScene(*sequence, localized, trajectory, stereo, summary, report);
  summary.seconds = watch.ElapsedSeconds();
  report["seconds"] = summary.seconds;
  report["bad_frames"] = frame_reader.bad_frames().size();
  const bool interrupted = frames_run < end - first && InterruptRequested();
  report["status"] = interrupted                   ? "interrupted"
                     : frame_reader.TooManyInRow() ? "stopped_bad_frames"
                                                   : "complete";
  WriteFileAtomically(options.output / "localize.json", report.dump(2) + "\n");
  if (interrupted) {
    throw Interrupted(InterruptSignal(),
                      fmt::format("interrupted by {} after {} of {} frames; what was localized "
                                  "is saved in {}",
                                  InterruptName(), frames_run, end - first, options.output.string()));
  }
  if (frame_reader.TooManyInRow()) {
    throw InputError(options.output,
                     fmt::format("{} bad frames in a row (the last: {}); localization stopped "
                                 "and saved what it did in this folder",
                                 frame_reader.bad_in_row(), frame_reader.bad_frames().back().reason));
  }
  return summary;
}

}  // namespace semslam
