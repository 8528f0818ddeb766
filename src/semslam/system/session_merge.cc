#include "semslam/system/session_merge.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <unordered_map>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/log_file.h"
#include "semslam/core/progress.h"
#include "semslam/core/timing.h"
#include "semslam/eval/trajectory_metrics.h"
#include "semslam/geo/gps.h"
#include "semslam/geo/gps_fusion.h"
#include "semslam/io/sequence.h"
#include "semslam/landmarks/catalogue.h"
#include "semslam/loop/loop_closer.h"
#include "semslam/map/map_file.h"
#include "semslam/map/map_validation.h"
#include "semslam/mapping/map_georeference.h"
#include "semslam/report/geo_outputs.h"
#include "semslam/report/html_report.h"
#include "semslam/system/atlas_outputs.h"
#include "semslam/system/merge_inputs.h"
#include "semslam/system/merge_outputs.h"
#include "semslam/system/merge_places.h"
#include "semslam/system/merge_session_frames.h"
#include "semslam/system/run_output_dir.h"
#include "semslam/system/slam_system.h"

namespace semslam {

namespace fs = std::filesystem;

void SessionMergeOptions::Check() const {
  Require(!runs.empty(), "merge: no run folder given");
  Require(!output.empty(), "merge: no output folder given");
  Require(global_ba_iterations > 0, "merge: global_ba_iterations must be positive");
  Require(global_ba_refine_iterations > 0, "merge: global_ba_refine_iterations must be positive");
  Require(global_ba_window_keyframes >= 2, "merge: global_ba_window_keyframes must be >= 2");
  // One drive given twice would be two sessions of the same frames, each the other's perfect loop.
  std::set<std::filesystem::path> seen;
  for (const std::filesystem::path& run : runs) {
    std::error_code ec;
    const std::filesystem::path key = std::filesystem::weakly_canonical(run, ec);
    Require(seen.insert(ec ? run : key).second, fmt::format("merge: --maps names {} twice", run.string()));
  }
}

namespace {

// Every drive's GPS fixes in one pose graph with the merged map's own links (geo/gps_fusion.h), the drives
// one after another in time and frame index: each merge took one map's place in the world and the others
// followed by what vision saw, so the fixes of all drives now place the whole map together. The map is moved
// where the fusion put its keyframes. Returns run.json's figures, or null when no drive had fixes enough.
nlohmann::json FuseSessionsWithGps(SlamSystem& slam, std::uint32_t main_map,
                                   const std::vector<SessionRecord>& sessions, const EnuFrame& world,
                                   bool stereo, FrameScale frame_scale) {
  GpsFusionInput input;
  input.enu_from_map = Sim3d();  // the map is in the world already
  GpsFusionOptions options;
  options.alignment.estimate_scale = !stereo;
  // Each drive's map bent its scale to its own fixes in its run: the merge's fusion holds the merged map's
  // scale by all its covisibility and places the drives, rather than bend them to the same fixes again.
  options.one_pass_covisibility_carries_scale = true;
  options.sampling.time_offset_s = 0.0;  // each drive's fixes are moved into its frames' time below
  bool any = false;
  for (size_t k = 0; k < sessions.size(); ++k) {
    const SessionRecord& s = sessions[k];
    if (!s.input || s.input->gps.empty()) continue;
    std::vector<FramePose> frames = SessionFrames(s, frame_scale, nullptr);
    std::erase_if(frames, [&](const FramePose& f) { return f.map_id != main_map || f.predicted; });
    if (frames.size() < 2) continue;
    GpsLog log;
    try {
      log = ReadGps(s.input->gps);
      if (log.times_are_frames) {
        const std::unique_ptr<ImageSequence> sequence =
            OpenSequence(s.input->sequence, {s.input->camera, false});
        TimeFixesByFrame(log, FrameTimestamps(*sequence, 0, sequence->size()));
      }
    } catch (const std::exception& e) {
      spdlog::warn("session {}: its GPS log is not used: {}", s.id, e.what());
      continue;
    }
    std::vector<double> times;
    for (const FramePose& f : frames) times.push_back(f.timestamp);
    const double offset = GuessTimeOffset(log.fixes, times);
    const double shift = 1e6 * static_cast<double>(k + 1);
    const size_t index_shift = 10'000'000 * (k + 1);
    for (FramePose f : frames) {
      f.timestamp += shift;
      f.frame_index += index_shift;
      input.frames.push_back(f);
    }
    {
      auto lock = slam.map().ReadLock();
      for (FramePose kf : SessionKeyFrames(s)) {
        if (kf.map_id != main_map) continue;
        kf.frame_index += index_shift;
        kf.timestamp += shift;
        input.keyframes.push_back(kf);
      }
    }
    for (GpsFix fix : log.fixes) {
      fix.timestamp += shift - offset;
      input.fixes.push_back(fix);
    }
    if (!any && s.input->lever_arm) options.antenna_in_camera_m = *s.input->lever_arm;
    options.sampling.every_n_frames = s.input->gps_every;
    any = true;
  }
  if (!any) return nullptr;
  std::sort(input.keyframes.begin(), input.keyframes.end(),
            [](const FramePose& a, const FramePose& b) { return a.frame_index < b.frame_index; });
  std::stable_sort(input.fixes.begin(), input.fixes.end(),
                   [](const GpsFix& a, const GpsFix& b) { return a.timestamp < b.timestamp; });
  input.edges = slam.KeyFrameEdges(input.keyframes);
  const std::optional<GpsFusionResult> result = FuseGps(input, world, options);
  if (!result) {
    spdlog::warn("the drives' GPS fixes do not place the merged map: it stays where the merges put it");
    return nullptr;
  }
  std::unordered_map<std::uint64_t, Sim3d> world_from_keyframe;
  for (size_t i = 0; i < input.keyframes.size(); ++i) {
    world_from_keyframe[static_cast<std::uint64_t>(input.keyframes[i].keyframe_id)] =
        result->keyframe_enu_from_camera[i];
  }
  {
    auto lock = slam.map().WriteLock();
    MoveMapIntoWorld(slam.map(), main_map, world_from_keyframe, result->georeference.enu_from_map);
  }
  spdlog::info("the merged map fused with its drives' GPS: {} of {} fixes kept, {:.2f} m RMSE",
               result->num_inliers, result->samples.size(), result->inlier_rmse_m);
  return {{"samples", result->samples.size()},
          {"inliers", result->num_inliers},
          {"fit_rmse_m", result->inlier_rmse_m}};
}

// The runs to merge: one sensor mode for all.
std::vector<InputRun> ReadRuns(const std::vector<fs::path>& dirs) {
  std::vector<InputRun> runs;
  for (const fs::path& dir : dirs) runs.push_back(ReadInputRun(dir));
  for (const InputRun& r : runs) {
    if (r.mode != runs.front().mode) {
      throw InvalidArgument(
          fmt::format("merge: {} holds a {} map and {} a {} one; monocular and stereo maps are not "
                      "merged",
                      runs.front().dir.string(), runs.front().mode, r.dir.string(), r.mode));
    }
  }
  return runs;
}

// The system that holds the atlas: its camera and rig are the first map's (it tracks no frame).
std::unique_ptr<SlamSystem> MakeAtlasSystem(const InputRun& first_run, bool stereo,
                                            const SessionMergeOptions& options) {
  PinholeCamera camera;
  std::optional<StereoRig> rig;
  {
    Map first;
    const MapFileContents contents = ReadMapFile(first_run.dir / "map.semslam", first);
    auto lock = first.ReadLock();
    const KeyFrame* kf = first.KeyFrames().front();
    camera = contents.cameras.begin()->second.camera;
    rig = kf->data().stereo;
  }
  SlamOptions slam_options;
  slam_options.mode = stereo ? SensorMode::kStereo : SensorMode::kMonocular;
  slam_options.pacing = Pacing::kSynchronous;
  slam_options.vocabulary = options.vocabulary;
  slam_options.loop.global_ba = false;  // one at the end, over every merged map
  slam_options.loop.global_ba_window_keyframes = options.global_ba_window_keyframes;
  slam_options.final_global_ba = options.global_ba;
  slam_options.final_global_ba_iterations = options.global_ba_iterations;
  slam_options.final_global_ba_refine_iterations = options.global_ba_refine_iterations;
  slam_options.final_refine_intrinsics = false;  // each map keeps the camera its run fitted
  if (stereo && !rig)
    throw InputError(first_run.dir / "map.semslam", "a stereo run's map holds no stereo keyframe");
  return std::make_unique<SlamSystem>(slam_options, camera, stereo ? rig : std::nullopt);
}

// The runs' maps in one atlas, and where each session's frames are.
struct Atlas {
  std::vector<SessionRecord> sessions;
  std::map<std::uint32_t, Georeference> in_world;  // by map id, as each run placed it
  std::vector<fs::path> catalogues;                // the runs' landmark catalogues
};

Atlas AppendRuns(SlamSystem& slam, const std::vector<InputRun>& runs) {
  Map& map = slam.map();
  Atlas atlas;
  std::vector<SessionRecord>& sessions = atlas.sessions;
  for (const InputRun& run : runs) {
    const MapFileContents contents = slam.AppendMap(run.dir / "map.semslam");
    auto lock = map.ReadLock();
    const std::uint32_t first_session = contents.first_session;
    const std::uint32_t last_session = static_cast<std::uint32_t>(map.sessions().size() - 1);
    for (std::uint32_t s = first_session; s <= last_session; ++s) {
      SessionRecord& record = sessions.emplace_back();
      record.id = s;
      record.run = run.dir;
      record.first_map_id = contents.first_map_id;
      const std::uint32_t in_file = s - first_session;
      if (auto it = run.sessions.find(in_file); it != run.sessions.end()) record.input = it->second;
      if (auto it = run.sessions.find(kLastSession); it != run.sessions.end() && s == last_session)
        record.input = it->second;
    }
    for (KeyFrame* kf : map.KeyFrames()) {
      if (kf->session() < first_session) continue;
      sessions[kf->session()].anchors[kf->map_id()][kf->frame_id()] = {kf, kf->world_from_camera(),
                                                                       kf->scale_correction()};
    }
    if (const auto it = contents.extra_sections.find("geo"); it != contents.extra_sections.end()) {
      std::uint32_t largest = contents.first_map_id;
      size_t most = 0;
      for (const std::uint32_t id : map.MapIds()) {
        if (id >= contents.first_map_id && map.NumKeyFramesOfMap(id) > most) {
          most = map.NumKeyFramesOfMap(id);
          largest = id;
        }
      }
      const GeoContext geo = ParseGeoSection(
          it->second, fs::path((run.dir / "map.semslam").string() + "#geo"), largest - contents.first_map_id);
      for (const auto& [id, georeference] : geo.maps)
        atlas.in_world.emplace(id + contents.first_map_id, georeference);
    }
    atlas.catalogues.insert(atlas.catalogues.end(), run.catalogues.begin(), run.catalogues.end());
  }
  for (const SessionRecord& s : sessions) {
    if (!s.input)
      spdlog::info("session {} ({}): no frames of its own are known, only its keyframes", s.id,
                   map.sessions()[s.id].name);
  }
  return atlas;
}

// One world frame for every map a run placed in it: its ENU origin is the first such run's.
struct World {
  std::optional<EnuFrame> frame;
  std::set<std::uint32_t> maps;  // the maps in it
};

World MoveMapsIntoOneWorld(Map& map, const std::map<std::uint32_t, Georeference>& in_world) {
  World world;
  for (const auto& [map_id, georeference] : in_world) {
    if (!world.frame) world.frame = georeference.enu_frame;
    const Sim3d world_from_map = EnuFromEnu(*world.frame, georeference.enu_frame) * georeference.enu_from_map;
    auto lock = map.WriteLock();
    if (map.NumKeyFramesOfMap(map_id) == 0) continue;
    MoveMapIntoWorld(map, map_id, {}, world_from_map);
    world.maps.insert(map_id);
    spdlog::info("map {} is in the world (its run's GPS placement){}", map_id,
                 georeference.local ? "; its per-keyframe corrections are left out" : "");
  }
  return world;
}

// Maps in the world that no place tied, joined by their GPS placement into the largest of them.
struct GpsJoins {
  std::optional<std::uint32_t> main_map;  // the map in the world
  size_t count = 0;
  nlohmann::json events = nlohmann::json::array();
};

GpsJoins JoinMapsInTheWorld(Map& map, const std::set<std::uint32_t>& world_maps) {
  GpsJoins joins;
  auto lock = map.WriteLock();
  for (const std::uint32_t id : map.MapIds()) {
    if (!world_maps.count(id)) continue;
    if (!joins.main_map || map.NumKeyFramesOfMap(id) > map.NumKeyFramesOfMap(*joins.main_map))
      joins.main_map = id;
  }
  for (const std::uint32_t id : map.MapIds()) {
    if (!world_maps.count(id) || id == *joins.main_map) continue;
    map.MergeMapInto(id, *joins.main_map);
    ++joins.count;
    joins.events.push_back({{"map", id}, {"into", *joins.main_map}});
    spdlog::info("map {} joined map {} in the world through the GPS", id, *joins.main_map);
  }
  return joins;
}

// A point that no adjustment held (seen from nearly one direction) may have run off towards infinity: not a
// place of the map, and one the map file refuses.
void RemoveRunawayPoints(Map& map) {
  auto lock = map.WriteLock();
  size_t culled = 0;
  for (MapPoint* p : map.MapPoints()) {
    if (p->position().allFinite() && p->position().cwiseAbs().maxCoeff() <= kMaxMapCoordinateM / 10) continue;
    p->SetBad();
    map.EraseMapPoint(p);
    ++culled;
  }
  if (culled > 0) spdlog::info("{} map points far beyond the map removed", culled);
}

}  // namespace

SessionMergeSummary MergeSessions(const SessionMergeOptions& options) {
  options.Check();
  Stopwatch watch;
  const std::vector<InputRun> runs = ReadRuns(options.runs);
  const bool stereo = runs.front().mode == "stereo";
  const FrameScale frame_scale = stereo ? FrameScale::kKeyFrame : FrameScale::kNeighbourSpacing;
  OutputDirOptions output_dir_options;
  output_dir_options.overwrite = options.overwrite;
  output_dir_options.command = "merge";
  output_dir_options.inputs = options.runs;
  output_dir_options.inputs.push_back(options.vocabulary);
  const RunOutputDir output_dir(options.output, output_dir_options);
  const LogFile log(options.output / kOutputLogFile, ProvenanceLines(options.provenance));
  const std::unique_ptr<SlamSystem> system = MakeAtlasSystem(runs.front(), stereo, options);
  SlamSystem& slam = *system;
  Map& map = slam.map();

  // 1. The atlas, and where each session's frames are.
  Atlas atlas = AppendRuns(slam, runs);
  std::vector<SessionRecord>& sessions = atlas.sessions;

  // 2. One world frame for every map a run placed in it.
  World world = MoveMapsIntoOneWorld(map, atlas.in_world);

  // 3. Place recognition across maps, then between the drives of each merged map.
  std::string status = "ok";
  PlaceRecognitionSummary places;
  if (options.place_recognition) {
    PlaceRecognitionOptions place_options;
    place_options.loops_between_drives = options.loops_between_drives;
    place_options.show_progress = options.show_progress;
    places = RecognizePlacesAcrossDrives(slam, world.maps, place_options);
    if (places.interrupted) status = "interrupted";
  }

  // 4. The final bundle adjustment of each map.
  slam.Finish();

  // 5. Maps in the world that no place tied: joined by their GPS placement.
  const GpsJoins joins = JoinMapsInTheWorld(map, world.maps);
  const std::optional<std::uint32_t>& world_main = joins.main_map;

  // 6. The merged map in the world: placed by every drive's GPS.
  nlohmann::json gps_fusion = nullptr;
  if (world_main && options.gps_fusion)
    gps_fusion = FuseSessionsWithGps(slam, *world_main, sessions, *world.frame, stereo, frame_scale);
  RemoveRunawayPoints(map);

  // 7. Outputs.
  MergeOutputOptions output_options;
  output_options.folder = options.output;
  output_options.stereo = stereo;
  output_options.frame_scale = frame_scale;
  if (world_main) output_options.world = world.frame;
  output_options.catalogues = atlas.catalogues;
  size_t num_keyframes = 0, num_points = 0, num_maps = 0;
  {
    auto lock = map.ReadLock();
    output_options.main_map = world_main.value_or(map.MapWithMostKeyFrames());
    num_keyframes = map.NumKeyFrames();
    num_points = map.NumMapPoints();
    num_maps = map.MapIds().size();
  }
  const std::uint32_t main_map = output_options.main_map;
  const std::vector<fs::path>& catalogues = atlas.catalogues;
  const Alignment alignment = stereo ? Alignment::kSe3 : Alignment::kSim3;
  const MergeOutputs outputs = WriteMergeOutputs(map, sessions, output_options);
  const GeoOutputs& geo_outputs = outputs.geo;
  MapFileContents map_sections;
  map_sections.extra_sections = geo_outputs.map_sections;
  slam.SaveMap(options.output / "map.semslam", map_sections);

  nlohmann::json merge_events = nlohmann::json::array();
  for (const LoopEvent& e : slam.Merges()) {
    nlohmann::json event = LoopEventJson(e);
    event["map"] = e.map_id;
    event["into"] = e.matched_map_id;
    merge_events.push_back(std::move(event));
  }
  nlohmann::json catalogue_json = nlohmann::json::array();
  for (const fs::path& c : catalogues) catalogue_json.push_back(fs::absolute(c).string());
  nlohmann::json run_json = {
      {"command", "merge"},
      {"status", status},
      {"mode", stereo ? "stereo" : "mono"},
      {"runs", nlohmann::json::array()},
      {"keyframes", num_keyframes},
      {"points", num_points},
      {"landmark_catalogues", catalogue_json},
      {"seconds", watch.ElapsedSeconds()},
      {"peak_rss_mib", PeakRssMiB()},
  };
  for (const InputRun& r : runs) run_json["runs"].push_back(r.dir.string());
  run_json["maps"] = {{"count", num_maps},
                      {"main_map", main_map},
                      {"place_merges", places.merges},
                      {"session_loops", places.session_loops},
                      {"merges_not_confirmed", places.not_confirmed},
                      {"merge_events", merge_events},
                      {"gps_joins", joins.events},
                      {"sessions", outputs.sessions}};
  if (outputs.city_ate) run_json["ate_rmse_city"] = *outputs.city_ate;
  run_json["gps_fusion"] = gps_fusion;
  run_json["ate_alignment"] = AlignmentName(alignment);
  run_json["classes"] = ClassCountsJson(CountLabels(outputs.semantic_points));
  run_json["geo"] = nlohmann::json::parse(geo_outputs.summary.ToJson());
  run_json["landmark_evaluation"] = outputs.landmark_evaluation;
  run_json["provenance"] = ProvenanceJson(options.provenance);
  WriteFileAtomically(options.output / "run.json", run_json.dump(2) + "\n");
  WriteFileAtomically(options.output / "timing.json", TimingJson(slam.timing()).dump(2) + "\n");
  try {
    WriteHtmlReport(options.output);
  } catch (const std::exception& e) {
    spdlog::warn("no report: {}", e.what());
  }
  spdlog::info(
      "merged {} sessions of {} runs: {} maps left, {} merged by place recognition, {} joined by GPS, {} "
      "loops between drives",
      sessions.size(), runs.size(), num_maps, places.merges, joins.count, places.session_loops);

  SessionMergeSummary summary;
  summary.sessions = sessions.size();
  summary.maps = num_maps;
  summary.place_merges = places.merges;
  summary.session_loops = places.session_loops;
  summary.gps_joins = joins.count;
  summary.seconds = watch.ElapsedSeconds();
  return summary;
}

}  // namespace semslam
