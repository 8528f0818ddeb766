#include "semslam/system/sequence_runner.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/log_file.h"
#include "semslam/core/progress.h"
#include "semslam/geo/gps.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/landmarks/catalogue.h"
#include "semslam/report/geo_outputs.h"
#include "semslam/report/html_report.h"
#include "semslam/semantics/neighbour_labels.h"
#include "semslam/semantics/segmenter.h"
#include "semslam/semantics/semantic_outputs.h"
#include "semslam/system/atlas_georeference.h"
#include "semslam/system/atlas_outputs.h"
#include "semslam/system/frame_reader.h"
#include "semslam/system/frame_trajectory.h"
#include "semslam/system/run_evaluation.h"
#include "semslam/system/run_input_checks.h"
#include "semslam/system/run_output_dir.h"
#include "semslam/system/slam_config.h"

namespace semslam {

namespace fs = std::filesystem;

void RunOptions::Check() const {
  Require(!sequence.empty(), "run: --sequence is required");
  Require(!output.empty(), "run: --out is required");
  Require(first_frame < end_frame, "run: the frame range is empty");
  Require(gps_every >= 1, "run: --gps-every must be at least 1 frame");
  Require(std::isfinite(camera_height_m) && camera_height_m > 0,
          "run: --camera-height must be a positive number of metres");
  Require(!slam.localization_only || !map_in.empty(),
          "run: --localization-only needs --map-in (the map to track against without changing it)");
  Require(!slam.exclude_dynamic || (segmenter != "none" && !segmenter.empty()),
          "run: --exclude-dynamic needs a --segmenter (it keeps points out by their labels)");
  // Paths are recorded in run.json and the report (UTF-8): refused now rather than after the last frame.
  RequireUtf8Argument(sequence, "--sequence");
  RequireUtf8Argument(output, "--out");
  RequireUtf8Argument(map_in, "--map-in");
  RequireUtf8Argument(gps, "--gps");
  RequireUtf8Argument(landmarks, "--landmarks");
  RequireUtf8Argument(segmenter, "--segmenter");
  slam.Check();
}

void ParseFrameRange(const std::string& text, size_t* first, size_t* end) {
  const size_t colon = text.find(':');
  Require(colon != std::string::npos, fmt::format("frame range '{}' must look like A:B", text));
  auto parse = [&](std::string_view part, size_t fallback) {
    if (part.empty()) return fallback;
    size_t value = 0;
    const auto [ptr, ec] = std::from_chars(part.data(), part.data() + part.size(), value);
    Require(ec == std::errc() && ptr == part.data() + part.size(),
            fmt::format("frame range '{}': '{}' is not a frame number", text, part));
    return value;
  };
  const std::string_view view(text);
  *first = parse(view.substr(0, colon), 0);
  *end = parse(view.substr(colon + 1), std::numeric_limits<size_t>::max());
  Require(*first < *end, fmt::format("frame range '{}' is empty", text));
}

size_t CheckFrameRange(const ImageSequence& sequence, size_t first, size_t end, bool stereo,
                       std::string_view command) {
  const size_t clamped = std::min(end, sequence.size());
  if (first >= clamped) {
    throw InvalidArgument(fmt::format("{}: frames {}:{} are outside the sequence's {} frames", command, first,
                                      end, sequence.size()));
  }
  if (stereo && !sequence.stereo()) {
    throw InputError(sequence.directory(),
                     "stereo mode needs a second camera (image_1/ and P1 in calib.txt)");
  }
  if (end != std::numeric_limits<size_t>::max() && end > clamped) {
    spdlog::warn("{}: frames {}:{} reach past the sequence's {} frames: frames {}..{} are used", command,
                 first, end, sequence.size(), first, clamped - 1);
  }
  return clamped;
}

namespace {

// The first frame of the run that has a tracked pose (-1: none).
long long FirstTrackedFrame(const SlamSystem& slam) {
  for (const FramePose& pose : slam.AllFramePoses()) {
    if (!pose.predicted) return static_cast<long long>(pose.frame_index);
  }
  return -1;
}

// A map that never started, or started late, says so.
void WarnAboutInitialization(long long first_tracked, size_t first, size_t end) {
  if (first_tracked < 0) {
    spdlog::warn(
        "no map was started: none of the {} frames was tracked (too little texture or parallax, or "
        "too few frames?)",
        end - first);
    return;
  }
  const auto delay = static_cast<size_t>(first_tracked) - first;
  if (delay > 20) {
    spdlog::warn("the map started late: its first frame is {}, {} frames into the run", first_tracked, delay);
  }
}

// How the frame loop ended, for run.json and the exit status.
struct FrameLoopEnd {
  std::string status = "complete";
  size_t last_frame = 0;  // the last frame read (tracked or skipped)
  size_t frames_run = 0;  // frames read, bad ones included
};

nlohmann::json BadFramesJson(const FrameReader& reader) {
  constexpr size_t kListed = 20;
  nlohmann::json listed = nlohmann::json::array();
  for (size_t k = 0; k < std::min(kListed, reader.bad_frames().size()); ++k) {
    listed.push_back({{"frame", reader.bad_frames()[k].frame}, {"reason", reader.bad_frames()[k].reason}});
  }
  return {{"count", reader.bad_frames().size()}, {"first", listed}};
}

// After the outputs are saved: a run that did not go through every frame says why, through the exit status.
void ReportEarlyEnd(const FrameLoopEnd& loop, const FrameReader& reader, size_t first, size_t end,
                    const std::filesystem::path& output) {
  if (loop.status == "interrupted") {
    throw Interrupted(
        InterruptSignal(),
        fmt::format("interrupted by {} after {} of {} frames; the trajectory so far, the map and "
                    "run.json (status \"interrupted\") are saved in {}",
                    InterruptName(), loop.frames_run, end - first, output.string()));
  }
  if (loop.status == "stopped_bad_frames") {
    const BadFrame& last = reader.bad_frames().back();
    throw InputError(output,
                     fmt::format("{} bad frames in a row up to frame {} (the last: {}); the run stopped "
                                 "and saved frames {}..{} in this folder",
                                 reader.bad_in_row(), last.frame, last.reason, first, loop.last_frame));
  }
}

// The main map's place in the world for the outputs: where its GPS put it this run (the map now lies in the
// ENU frame itself), or where an earlier run did.
std::optional<GeoInputs::Placed> PlacedMainMap(const std::optional<AtlasGeoreference>& placed_by_gps,
                                               const std::map<std::uint32_t, Georeference>& known,
                                               std::uint32_t main_map, const std::optional<GpsLog>& log) {
  if (placed_by_gps && placed_by_gps->enu &&
      std::count(placed_by_gps->world_maps.begin(), placed_by_gps->world_maps.end(), main_map) > 0) {
    GeoInputs::Placed placed{Georeference(*placed_by_gps->enu, Sim3d())};
    for (const MapGeoreferenceSummary& m : placed_by_gps->maps) {
      if (!m.in_world || (m.map_id != main_map && m.joined_into != main_map)) continue;
      placed.samples.insert(placed.samples.end(), m.gps_samples.begin(), m.gps_samples.end());
      placed.inliers.insert(placed.inliers.end(), m.gps_inliers.begin(), m.gps_inliers.end());
      if (m.map_id == main_map) {
        for (const auto& [frame, enu] : m.single_similarity_frames)
          placed.single_similarity_enu.push_back(enu);
        placed.fit_rmse_m = m.fit_rmse_m;
        placed.single_similarity_rmse_m = m.single_similarity_rmse_m;
      }
    }
    if (log) {
      placed.gps_format = log->format;
      placed.gps_fixes = static_cast<int>(log->fixes.size());
      placed.gps_skipped = static_cast<int>(log->skipped.size());
    }
    placed.time_offset_s = placed_by_gps->time_offset_s;
    return placed;
  }
  const bool placed_this_run =
      placed_by_gps &&
      std::any_of(placed_by_gps->maps.begin(), placed_by_gps->maps.end(),
                  [&](const MapGeoreferenceSummary& m) { return m.map_id == main_map && m.in_world; });
  if (const auto it = known.find(main_map); it != known.end() && !placed_this_run) {
    return GeoInputs::Placed{it->second};
  }
  return std::nullopt;
}

// The other maps in the world: placed this run (in its ENU frame), or by an earlier one and not touched
// since.
std::map<std::uint32_t, Georeference> OtherMapsInTheWorld(
    const std::optional<AtlasGeoreference>& placed_by_gps, const std::map<std::uint32_t, Georeference>& known,
    std::uint32_t main_map) {
  std::map<std::uint32_t, Georeference> maps = known;
  if (placed_by_gps && placed_by_gps->enu) {
    for (const MapGeoreferenceSummary& m : placed_by_gps->maps) {
      maps.erase(
          m.map_id);  // a map this run moved, or left out of the world, is no longer where it was known
      if (m.in_world && !m.joined_into)
        maps.insert_or_assign(m.map_id, Georeference(*placed_by_gps->enu, Sim3d()));
    }
  }
  maps.erase(main_map);
  return maps;
}

nlohmann::json MapsInTheWorldJson(const AtlasGeoreference& atlas) {
  nlohmann::json maps = nlohmann::json::array();
  for (const MapGeoreferenceSummary& m : atlas.maps) {
    nlohmann::json entry = {{"map", m.map_id},
                            {"frames", m.frames},
                            {"keyframes", m.keyframes},
                            {"gps_samples", m.samples},
                            {"gps_inliers", m.inliers},
                            {"fit_rmse_m", m.fit_rmse_m},
                            {"single_similarity_rmse_m", m.single_similarity_rmse_m},
                            {"in_world", m.in_world}};
    if (!m.in_world) entry["reason"] = m.reason;
    if (m.roll_from_cameras) entry["roll_from_cameras"] = true;
    if (m.joined_into) entry["joined_into"] = *m.joined_into;
    maps.push_back(std::move(entry));
  }
  return maps;
}

// Frames first..end-1 through the system, one after another; tracking.csv says how each went. Stops at a
// signal (after the frame in hand) or at too many bad frames in a row.
FrameLoopEnd TrackFrames(SlamSystem& slam, const ImageSequence& sequence, size_t first, size_t end,
                         FrameReader& frame_reader, ProgressReporter& progress,
                         const fs::path& tracking_csv_path) {
  // Per frame: how tracking went, how big the map was (tracking time against map size) and the memory the
  // process held (resident set, MiB).
  std::string tracking_csv = "frame,state,tracking_ms,matched,keyframes,map_points,rss_mib\n";
  FrameLoopEnd loop;
  for (size_t i = first; i < end; ++i) {
    if (InterruptRequested()) {  // the frame before was finished: stop here and save
      loop.status = "interrupted";
      break;
    }
    loop.last_frame = i;
    ++loop.frames_run;
    ScopedTimer frame_timer(slam.timing(), "frame");  // the whole system per frame: loading, tracking, pacing
    const std::optional<FrameImages> images = frame_reader.Read(i);
    size_t keyframes = 0, points = 0;
    if (images) {
      const TrackingResult result =
          slam.ProcessFrame(i, sequence.Timestamp(i), images->left, images->right, {}, images->color);
      {
        auto lock = slam.map().ReadLock();
        keyframes = slam.map().NumKeyFrames();
        points = slam.map().NumMapPoints();
      }
      tracking_csv +=
          fmt::format("{},{},{:.3f},{},{},{},{:.1f}\n", i, ToString(result.state), result.milliseconds,
                      result.matched_points, keyframes, points, CurrentRssMiB());
      progress.Update(i - first + 1, fmt::format("{}, {} keyframes", ToString(result.state), keyframes));
      continue;
    }
    tracking_csv += fmt::format("{},bad_frame,0,0,,,{:.1f}\n", i, CurrentRssMiB());
    if (frame_reader.TooManyInRow()) {
      loop.status = "stopped_bad_frames";
      break;
    }
  }
  WriteFileAtomically(tracking_csv_path, tracking_csv);
  return loop;
}

// Weak labels (one observation, or a tie of two) take their confident neighbours' class as one more
// observation (semantics/neighbour_labels.h): on the 400-frame city with 25 % label noise, 3D label accuracy
// 94.3 % -> 96.0 % (stereo), 95.8 % -> 97.0 % (mono). Returns how many did.
size_t FuseLabelsOfNeighbours(Map& map) {
  auto lock = map.WriteLock();
  std::vector<Eigen::Vector3d> positions;
  std::vector<LabelDistribution*> labels;
  for (MapPoint* point : map.MapPoints()) {
    if (point->is_bad()) continue;
    positions.push_back(point->position());
    labels.push_back(&point->labels());
  }
  const size_t labels_from_neighbours = FuseNeighbourLabels(positions, labels);
  spdlog::info("{} of {} map-point labels took their neighbours' class as one more observation",
               labels_from_neighbours, labels.size());
  return labels_from_neighbours;
}

}  // namespace

RunSummary RunSequence(const RunOptions& options) {
  options.Check();
  Stopwatch watch;
  const bool stereo = options.slam.mode == SensorMode::kStereo;
  const std::unique_ptr<ImageSequence> sequence = OpenSequence(options.sequence, {options.camera, stereo});
  const size_t first = options.first_frame;
  const size_t end = CheckFrameRange(*sequence, first, options.end_frame, stereo, "run");
  const std::vector<double> frame_times = FrameTimestamps(*sequence, first, end);
  // Inputs read after SLAM are checked now, so that a malformed file stops the run before its first frame.
  std::optional<GpsLog> gps_log;
  if (!options.gps.empty()) {
    gps_log = ReadGps(options.gps);
    TimeFixesByFrame(*gps_log, FrameTimestamps(*sequence, 0, sequence->size()));
    LogSkippedFixes(*gps_log);
    CheckGpsLog(*gps_log, frame_times);
  }
  std::optional<std::vector<Landmark>> catalogue;
  if (!options.landmarks.empty()) {
    catalogue = ReadLandmarks(options.landmarks);
    if (catalogue->empty()) throw InputError(options.landmarks, "the landmark catalogue holds no landmark");
    WarnAboutFarLandmarks(*catalogue, options.landmarks, gps_log);
  }
  // Writable, not in use by another run, and nothing of an earlier run left in it: before the first frame.
  OutputDirOptions output_dir_options;
  output_dir_options.overwrite = options.overwrite;
  output_dir_options.inputs = {options.sequence, options.map_in, options.gps, options.landmarks};
  const RunOutputDir output_dir(options.output, output_dir_options);
  const LogFile log(options.output / kOutputLogFile, ProvenanceLines(options.provenance));
  spdlog::info("sequence {} ({}{}), frames {}..{}, {} mode, camera {}", sequence->name(),
               sequence->directory().string(),
               sequence->camera_name().empty() ? "" : ", " + sequence->camera_name(), first, end - 1,
               stereo ? "stereo" : "monocular", sequence->camera().ToString());

  SlamSystem slam(options.slam, sequence->camera(), sequence->stereo());
  // Where a loaded map's maps sit in the world, when an earlier run placed them there.
  std::map<std::uint32_t, Georeference> known_georeferences;
  if (!options.map_in.empty()) {
    const MapFileContents contents = slam.LoadMap(options.map_in);
    if (const auto it = contents.extra_sections.find("geo"); it != contents.extra_sections.end()) {
      auto lock = slam.map().ReadLock();
      // A version-1 section placed the file's one map: today's largest.
      known_georeferences = ParseGeoSection(it->second, fs::path(options.map_in.string() + "#geo"),
                                            slam.map().MapWithMostKeyFrames())
                                .maps;
    }
  }
  slam.NameSession(sequence->name(), sequence->directory().string());
  SegmenterContext segmenter_context;
  segmenter_context.truth_label_dir = sequence->LabelDirectory();
  segmenter_context.seed = options.seed;
  segmenter_context.colour_images = sequence->IsColor();  // auto: SINet for colour, ESPNetv2 for grey
  std::shared_ptr<Segmenter> segmenter = MakeSegmenter(options.segmenter, segmenter_context);
  const std::string segmenter_description = segmenter ? segmenter->Describe() : "none";
  slam.EnableSegmentation(segmenter);

  ProgressReporter progress("run", end - first, options.show_progress);
  // A colour camera's frames go to the segmenter in colour and to tracking in grey (one decode for both).
  FrameReader frame_reader(*sequence, stereo, options.max_bad_frames_in_row, segmenter != nullptr);
  const FrameLoopEnd loop =
      TrackFrames(slam, *sequence, first, end, frame_reader, progress, options.output / "tracking.csv");
  slam.Finish();
  const size_t labels_from_neighbours = segmenter ? FuseLabelsOfNeighbours(slam.map()) : 0;
  // Every map with enough GPS is placed in the world, and the maps there are joined.
  std::optional<AtlasGeoreference> placed_by_gps;
  if (gps_log) {
    AtlasGeoreferenceOptions gps_options;
    gps_options.fuse = options.gps_fusion;
    gps_options.fusion.sampling.every_n_frames = options.gps_every;
    gps_options.fusion.alignment.estimate_scale = !stereo;
    gps_options.fusion.antenna_in_camera_m = options.gps_antenna_in_camera_m.value_or(
        sequence->GpsAntennaInCamera().value_or(Eigen::Vector3d::Zero()));
    placed_by_gps = GeoreferenceAtlas(slam, *gps_log, known_georeferences, gps_options);
  }
  const SlamStatistics stats = slam.Statistics();
  progress.Finish(fmt::format("{} of {} frames tracked, {} keyframes, {} points, {} loops", stats.tracked,
                              stats.frames, stats.keyframes, stats.map_points, stats.loops));

  const long long first_tracked = FirstTrackedFrame(slam);
  WarnAboutInitialization(first_tracked, first, end);
  const Trajectory trajectory = slam.FrameTrajectory();
  WriteTumTrajectory(options.output / "trajectory.tum", trajectory);
  WriteFramesCsv(options.output / "frames.csv", slam);
  WriteTumTrajectory(options.output / "keyframes.tum", slam.KeyFrameTrajectory());
  const DenseTrajectory kitti = WriteKittiFrameTrajectory(
      options.output / "trajectory.kitti", slam.FramePoses(), first, first + loop.frames_run,
      std::span<const double>(frame_times).first(loop.frames_run));  // skipped frames get their lines too
  const std::vector<SemanticPoint> semantic_points = SemanticPoints(slam.map());
  WriteSemanticPly(options.output / "semantic_map.ply", semantic_points);

  // GPS, landmarks, topology, objects and plots.
  GeoInputs geo;
  geo.frames = slam.FramePoses();
  geo.keyframes = slam.KeyFramePoses();
  geo.edges = slam.KeyFrameEdges();
  geo.map_id = slam.MainMapId();
  geo.placed = PlacedMainMap(placed_by_gps, known_georeferences, geo.map_id, gps_log);
  geo.other_maps = OtherMapsInTheWorld(placed_by_gps, known_georeferences, geo.map_id);
  if (!geo.placed) geo.gps = gps_log;  // no map in the world: the output step tries the main map alone
  geo.landmarks = std::move(catalogue);
  geo.landmarks_path = options.landmarks;
  geo.monocular = !stereo;
  geo.truth = sequence->GroundTruth();
  for (const SemanticPoint& p : semantic_points) {
    if (IsValidTrainId(p.label)) geo.points.push_back({p.position, p.label, p.confidence});
  }
  GeoOptions geo_options;
  geo_options.fuse = options.gps_fusion;
  geo_options.fusion.sampling.every_n_frames = options.gps_every;
  geo_options.road_scale->camera_height_m = options.camera_height_m;
  geo_options.fusion.antenna_in_camera_m = options.gps_antenna_in_camera_m.value_or(
      sequence->GpsAntennaInCamera().value_or(Eigen::Vector3d::Zero()));
  const GeoOutputs geo_outputs = WriteGeoOutputs(geo, options.output, geo_options);
  MapFileContents map_sections;
  map_sections.extra_sections = geo_outputs.map_sections;
  if (options.save_map && !options.slam.localization_only) {
    slam.SaveMap(options.output / "map.semslam", map_sections);
  }

  RunSummary summary;
  summary.statistics = stats;
  summary.seconds = watch.ElapsedSeconds();
  nlohmann::json run = {
      {"status", loop.status},
      {"sequence", sequence->directory().string()},
      {"camera", sequence->camera_name()},
      {"sequence_name", sequence->name()},
      {"mode", stereo ? "stereo" : "mono"},
      {"frames", stats.frames},
      {"first_frame", first},
      {"last_frame", loop.last_frame},
      {"frames_requested", end - first},
      {"bad_frames", BadFramesJson(frame_reader)},
      {"tracked", stats.tracked},
      {"with_pose", stats.with_pose},
      {"predicted", stats.predicted},
      {"first_tracked_frame", first_tracked},
      {"keyframes", stats.keyframes},
      {"points", stats.map_points},
      {"keyframes_created", stats.keyframes_created},
      {"points_created", stats.points_created},
      {"loops", stats.loops},
      {"relocalizations", stats.relocalizations},
      {"resets", stats.resets},
      {"seconds", summary.seconds},
      {"peak_rss_mib", PeakRssMiB()},
  };
  run["trajectory_kitti"] = {{"frames", kitti.source.size()},
                             {"own_pose", kitti.Count(PoseSource::kEstimated)},
                             {"first_pose", kitti.Count(PoseSource::kFirstPose)},
                             {"interpolated", kitti.Count(PoseSource::kInterpolated)},
                             {"motion_model", kitti.Count(PoseSource::kMotionModel)},
                             {"held", kitti.Count(PoseSource::kHeld)},
                             {"identity", kitti.Count(PoseSource::kNone)}};
  nlohmann::json loops = nlohmann::json::array();
  for (const LoopEvent& e : slam.Loops()) {
    nlohmann::json event = LoopEventJson(e);
    event["correction_m"] = e.correction_m;
    event["correction_deg"] = e.correction_deg;
    loops.push_back(std::move(event));
  }
  run["loop_events"] = loops;
  run["maps"] = AtlasJson(slam);
  run["intrinsics_refinement"] = IntrinsicsRefinementJson(slam);
  run["classes"] = ClassCountsJson(CountLabels(semantic_points));
  nlohmann::json segmentation = {{"segmenter", segmenter_description},
                                 {"segmented_keyframes", stats.segmented_keyframes},
                                 {"segmented_frames", stats.segmented_frames},
                                 {"labels_from_neighbours", labels_from_neighbours},
                                 {"exclude_dynamic", options.slam.exclude_dynamic}};
  if (const auto worker = slam.SegmentationStats()) {
    segmentation["submitted"] = worker->submitted;
    segmentation["skipped"] = worker->skipped;
    segmentation["failed"] = worker->failed;
    segmentation["median_ms"] = worker->segmentation_ms.median_ms;
  }
  run["segmentation"] = segmentation;
  const std::optional<AteResult> ate = TrajectoryAgainstTruth(*sequence, trajectory, stereo);
  summary.label_accuracy =
      AddLabelFigures(slam.map(), *sequence, ate, stereo, stats.segmented_keyframes, run);
  summary.ate_rmse =
      AddTrajectoryFigures(*sequence, ate, first, loop.last_frame, stereo, geo_outputs, geo, run);
  run["geo"] = nlohmann::json::parse(geo_outputs.summary.ToJson());
  if (placed_by_gps) run["geo"]["maps"] = MapsInTheWorldJson(*placed_by_gps);
  run["provenance"] = ProvenanceJson(options.provenance);
  run["config"] = EffectiveConfigJson(options, slam.options(), end);
  WriteFileAtomically(options.output / "config.yaml", SlamConfigToYaml(slam.options()));
  WriteFileAtomically(options.output / "run.json", run.dump(2) + "\n");
  WriteFileAtomically(options.output / "timing.json", TimingJson(slam.timing()).dump(2) + "\n");
  const HtmlReportResult report = WriteHtmlReport(options.output);
  spdlog::info("report: {} ({} of {} map points shown)", report.path.string(), report.points_shown,
               report.map_points);
  summary.status = loop.status;
  summary.bad_frames = frame_reader.bad_frames().size();
  ReportEarlyEnd(loop, frame_reader, first, end, options.output);
  return summary;
}

}  // namespace semslam
