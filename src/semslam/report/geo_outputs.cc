#include "semslam/report/geo_outputs.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/eval/trajectory_metrics.h"
#include "semslam/geo/georeference_json.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

namespace fs = std::filesystem;
using nlohmann::json;

void GeoOptions::Check() const {
  gps_read.Check();
  fusion.Check();
  Require(!time_offset_s || std::isfinite(*time_offset_s), "geo time_offset_s must be finite");
  landmarks.Check();
  Require(std::isfinite(osm_radius_m) && osm_radius_m > 0, "geo osm_radius_m must be positive");
  topology.Check();
  objects.Check();
  if (road_scale) road_scale->Check();
  plots.Check();
  Require(std::isfinite(raster_cell_m) && raster_cell_m > 0, "geo raster_cell_m must be positive");
}

std::string GeoSummary::ToJson() const {
  json j = {{"georeferenced", georeferenced},
            {"fused", fused},
            {"gps_format", gps_format},
            {"gps_fixes", gps_fixes},
            {"gps_skipped", gps_skipped},
            {"gps_samples", gps_samples},
            {"gps_inliers", gps_inliers},
            {"time_offset_s", time_offset_s},
            {"metres_per_map_unit", metres_per_map_unit},
            {"single_sim3_rmse_m", single_sim3_rmse_m},
            {"fused_rmse_m", fused_rmse_m},
            {"landmarks", landmarks},
            {"landmarks_associated", landmarks_associated},
            {"topology_nodes", topology_nodes},
            {"topology_landmark_nodes", topology_landmark_nodes},
            {"topology_turn_nodes", topology_turn_nodes},
            {"topology_edges", topology_edges},
            {"topology_revisited_nodes", topology_revisited_nodes},
            {"objects", objects},
            {"objects_per_class", objects_per_class},
            {"objects_metres_per_map_unit", objects_metres_per_map_unit},
            {"objects_scale_source", objects_scale_source},
            {"road_scale_keyframes", road_scale_keyframes},
            {"road_scale_spread", road_scale_spread},
            {"trajectory_frames", trajectory_frames}};
  return j.dump();
}

namespace {

void CheckInputs(const GeoInputs& inputs) {
  const auto check_order = [](const std::vector<FramePose>& poses, const char* what) {
    for (size_t i = 1; i < poses.size(); ++i) {
      Require(poses[i].frame_index > poses[i - 1].frame_index,
              fmt::format("geo outputs: {} must be in strictly increasing frame order", what));
    }
    for (const FramePose& p : poses) {
      Require(
          p.world_from_camera.translation.allFinite() && p.world_from_camera.rotation.coeffs().allFinite(),
          fmt::format("geo outputs: {} pose is not finite", what));
    }
  };
  check_order(inputs.frames, "frames");
  check_order(inputs.keyframes, "keyframes");
}

// The frames of the trajectory output: every tracked frame, or the keyframes when no frames are given.
const std::vector<FramePose>& TrajectoryFrames(const GeoInputs& inputs) {
  return inputs.frames.empty() ? inputs.keyframes : inputs.frames;
}

void WriteTrajectoryWgs84(const fs::path& path, const std::vector<FramePose>& frames, const Georeference& g) {
  std::string text = "t,lat,lon,alt\n";
  for (const FramePose& f : frames) {
    const Wgs84 w = g.enu_frame.ToWgs84(g.FrameToEnu(f.frame_index, f.world_from_camera.translation));
    text += fmt::format("{:.6f},{:.9f},{:.9f},{:.3f}\n", f.timestamp, w.latitude_deg, w.longitude_deg,
                        w.altitude_m);
  }
  WriteFileAtomically(path, text);
}

Points3d TrajectoryEnu(const std::vector<FramePose>& frames, const Georeference& g) {
  Points3d out;
  out.reserve(frames.size());
  for (const FramePose& f : frames)
    out.push_back(g.FrameToEnu(f.frame_index, f.world_from_camera.translation));
  return out;
}

PlotOptions Titled(PlotOptions options, std::string title) {
  if (options.title.empty()) options.title = std::move(title);
  return options;
}

// trajectory.png for every run; ate.png and rpe.png with a ground truth. In the level frame of the ground
// truth's first camera (metres), the estimate aligned to it as `semslam eval` does (Sim(3) monocular, SE(3)
// stereo); or, without a ground truth, the estimate in the level map frame (map units when monocular).
template <typename Write>
void WriteTrajectoryPlots(const GeoInputs& inputs, const std::vector<FramePose>& frames,
                          const PlotOptions& plots, const Write& write) {
  if (frames.size() < 2) return;
  const Sim3d level = LevelFromCameraWorld();
  Trajectory estimate;
  for (const FramePose& f : frames) estimate.push_back({f.timestamp, f.world_from_camera});
  PlotOptions options = plots;
  options.north_up = false;
  TrajectoryPlotInput input;
  std::optional<ErrorSeries> series;
  if (inputs.truth && inputs.truth->size() >= 2) {
    try {
      series =
          ComputeErrorSeries(estimate, *inputs.truth, inputs.monocular ? Alignment::kSim3 : Alignment::kSe3);
    } catch (const EvaluationError& e) {
      spdlog::warn("no error plots: {}", e.what());
    }
  }
  if (series) {
    for (const StampedPose& p : *inputs.truth) input.truth.push_back(level * p.world_from_camera.translation);
    for (const Rigid3d& p : series->aligned) input.estimate.push_back(level * p.translation);
    input.errors = series->ate.errors;
    input.estimate_label = inputs.monocular ? "estimate, Sim(3)-aligned" : "estimate, SE(3)-aligned";
    options.metres = true;
  } else {
    for (const FramePose& f : frames) input.estimate.push_back(level * f.world_from_camera.translation);
    options.metres = !inputs.monocular;
  }
  write("trajectory.png",
        RenderTrajectoryPlot(input, Titled(options, series ? "Trajectory and ground truth (top view)"
                                                           : "Trajectory (top view, map frame)")));
  if (!series) return;
  ErrorPlotInput ate{series->distance_m, series->ate.errors, "ATE (m)"};
  write("ate.png",
        RenderErrorPlot(ate, Titled(options, fmt::format("Absolute trajectory error ({} alignment)",
                                                         inputs.monocular ? "Sim(3)" : "SE(3)"))));
  ErrorPlotInput rpe{series->distance_m, series->rpe_trans_m, "RPE translation (m)"};
  rpe.distance_m.erase(rpe.distance_m.begin());
  rpe.error.erase(rpe.error.begin());
  write("rpe.png", RenderErrorPlot(rpe, Titled(options, "Relative pose error between consecutive frames")));
}

// What the GPS plot shows besides the samples: which were inliers, and the trajectory placed by one
// similarity (when the fusion placed the map).
struct GpsPlotData {
  std::vector<bool> sample_inliers;
  Points3d single_similarity_enu;  // per trajectory frame
};

// The map's place in the world: found before (inputs.placed), or from the GPS log (read, sampled every N
// frames, robust similarity, pose-graph fusion). Fills out.georeference, samples, alignment, fusion and the
// summary's GPS figures.
GpsPlotData PlaceByGps(const GeoInputs& inputs, const std::vector<FramePose>& trajectory,
                       const GeoOptions& options, GeoOutputs& out) {
  std::optional<GpsLog> log = inputs.gps;
  GeoSummary& summary = out.summary;
  GpsPlotData plot;
  std::vector<bool>& sample_inliers = plot.sample_inliers;
  Points3d& single_similarity_enu = plot.single_similarity_enu;
  if (inputs.placed) {
    const GeoInputs::Placed& placed = *inputs.placed;
    log.reset();
    out.georeference = placed.georeference;
    out.samples = placed.samples;
    sample_inliers = placed.inliers;
    single_similarity_enu = placed.single_similarity_enu;
    summary.fused = options.fuse;
    summary.gps_format = placed.gps_format;
    summary.gps_fixes = placed.gps_fixes;
    summary.gps_skipped = placed.gps_skipped;
    summary.time_offset_s = placed.time_offset_s;
    summary.gps_samples = static_cast<int>(placed.samples.size());
    summary.gps_inliers = static_cast<int>(std::count(placed.inliers.begin(), placed.inliers.end(), true));
    summary.fused_rmse_m = placed.fit_rmse_m;
    summary.single_sim3_rmse_m = placed.single_similarity_rmse_m;
  } else if (!log && !inputs.gps_path.empty()) {
    log = ReadGps(inputs.gps_path, options.gps_read);
    LogSkippedFixes(*log);  // a log passed in was reported by whoever read it
  }
  if (log) {
    summary.gps_format = log->format;
    summary.gps_fixes = static_cast<int>(log->fixes.size());
    summary.gps_skipped = static_cast<int>(log->skipped.size());
  }
  if (log && !log->fixes.empty() && !inputs.keyframes.empty()) {
    const EnuFrame enu = MakeEnuFrame(*log, inputs.enu_origin);
    std::vector<double> times;
    for (const FramePose& f : trajectory) times.push_back(f.timestamp);
    GpsFusionOptions fusion_options = options.fusion;
    fusion_options.sampling.time_offset_s =
        options.time_offset_s.value_or(GuessTimeOffset(log->fixes, times));
    fusion_options.alignment.estimate_scale = inputs.monocular;
    summary.time_offset_s = fusion_options.sampling.time_offset_s;
    if (options.fuse) {
      GpsFusionInput fusion_input{inputs.keyframes, inputs.frames, inputs.edges, log->fixes};
      out.fusion = FuseGps(fusion_input, enu, fusion_options);
      if (out.fusion) {
        out.georeference = out.fusion->georeference;
        out.alignment = out.fusion->prealignment;
        out.samples = out.fusion->samples;
        summary.fused = true;
        summary.gps_samples = static_cast<int>(out.fusion->samples.size());
        summary.gps_inliers = out.fusion->num_inliers;
        summary.fused_rmse_m = out.fusion->inlier_rmse_m;
      }
    } else {
      out.samples = SampleGpsPairs(Positions(trajectory), log->fixes, enu, fusion_options.sampling);
      summary.gps_samples = static_cast<int>(out.samples.size());
      out.alignment = AlignMapToGps(out.samples, fusion_options.alignment);
      if (out.alignment) {
        out.georeference = Georeference(enu, out.alignment->enu_from_map);
        summary.gps_inliers = out.alignment->num_inliers;
      }
    }
    if (out.alignment) {
      summary.single_sim3_rmse_m = out.alignment->inlier_rmse_m;
      sample_inliers = out.fusion ? out.fusion->inliers : out.alignment->inliers;
      if (out.fusion) {
        for (const FramePose& f : trajectory)
          single_similarity_enu.push_back(out.alignment->enu_from_map * f.world_from_camera.translation);
      }
    }
    if (!out.georeference) {
      spdlog::warn(
          "GPS: {} fixes did not determine the map's place in the world (too few samples every {} frames, "
          "or all on one line with no level camera to set the roll about it); no WGS84 outputs",
          log->fixes.size(), fusion_options.sampling.every_n_frames);
    }
  }
  return plot;
}

// The plots (plots/): trajectory, GPS, topology, semantic map and landmark membership, those the outputs
// allow.
void WriteGeoPlots(const GeoInputs& inputs, const std::vector<FramePose>& trajectory,
                   const GeoOptions& options, const GpsPlotData& gps_plot, const fs::path& plots_dir,
                   GeoOutputs& out) {
  const auto write = [&](const std::string& name, const cv::Mat& image) {
    WritePlot(plots_dir / name, image);
    out.files.push_back(plots_dir / name);
  };
  // Without GPS the map is shown level (the first camera looking up the page), in map units when monocular.
  const Georeference view_frame =
      out.georeference ? *out.georeference : Georeference(EnuFrame(Wgs84{0, 0, 0}), LevelFromCameraWorld());
  const Points3d trajectory_enu = TrajectoryEnu(trajectory, view_frame);
  PlotOptions view_options = options.plots;
  view_options.north_up = out.georeference.has_value();
  view_options.metres = out.georeference.has_value() || !inputs.monocular;
  WriteTrajectoryPlots(inputs, trajectory, options.plots, write);
  if (out.georeference && !out.samples.empty()) {
    GpsPlotInput gps;
    for (const GpsSample& sample : out.samples) gps.gps_enu.push_back(sample.enu);
    gps.gps_inliers = gps_plot.sample_inliers;
    gps.single_sim3_enu = gps_plot.single_similarity_enu;
    gps.trajectory_enu = trajectory_enu;
    write("gps.png",
          RenderGpsPlot(gps, Titled(options.plots, out.summary.fused
                                                       ? "GPS fixes and the fused SLAM trajectory"
                                                       : "GPS fixes and the transformed SLAM trajectory")));
  }
  if (out.topology)
    write("topology.png", RenderTopologyPlot(*out.topology, Titled(options.plots, "Topological map")));
  if (!inputs.points.empty()) {
    Points3d points_enu;
    std::vector<int> labels;
    points_enu.reserve(inputs.points.size());
    for (const LabeledPoint& p : inputs.points) {
      points_enu.push_back(view_frame.MapToEnu(p.position));
      labels.push_back(p.label);
    }
    write(
        "semantic_map.png",
        RenderSemanticMapPlot(points_enu, labels, trajectory_enu,
                              Titled(view_options, out.georeference ? "Semantic map (top view, north up)"
                                                                    : "Semantic map (top view, map frame)")));
  }
  if (out.georeference && !out.landmarks.empty()) {
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Eigen::Vector3d& p : trajectory_enu) {
      lo = lo.cwiseMin(p.head<2>());
      hi = hi.cwiseMax(p.head<2>());
    }
    for (const PlacedLandmark& l : out.landmarks) {
      lo = lo.cwiseMin(l.enu.head<2>());
      hi = hi.cwiseMax(l.enu.head<2>());
    }
    const double pad = 3.0 * options.landmarks.sigma_m;
    const MembershipRaster raster =
        RasterizeMembership(out.landmarks, lo.array() - pad, hi.array() + pad, options.raster_cell_m,
                            options.landmarks.sigma_m, 1'000'000);
    write("membership.png", RenderMembershipPlot(raster, out.landmarks, trajectory_enu,
                                                 Titled(options.plots, "Landmark membership m(x, y)")));
  }
}

}  // namespace

GeoOutputs WriteGeoOutputs(const GeoInputs& inputs, const fs::path& out_dir, const GeoOptions& options) {
  options.Check();
  CheckInputs(inputs);
  fs::create_directories(out_dir);
  GeoOutputs out;
  GeoSummary& summary = out.summary;
  const std::vector<FramePose>& trajectory = TrajectoryFrames(inputs);

  // 1. GPS: read, sample every N frames, robust similarity, pose-graph fusion; or the placement found before.
  const GpsPlotData gps_plot = PlaceByGps(inputs, trajectory, options, out);
  summary.georeferenced = out.georeference.has_value();
  if (out.georeference) summary.metres_per_map_unit = out.georeference->MetresPerMapUnit();

  const FramePositions keyframe_positions = Positions(inputs.keyframes);
  if (out.georeference) {
    const Georeference& g = *out.georeference;
    WriteFileAtomically(out_dir / "georeference.json", GeoreferenceToJson(g) + "\n");
    out.files.push_back(out_dir / "georeference.json");
    // 2. The WGS84 trajectory.
    WriteTrajectoryWgs84(out_dir / "trajectory_wgs84.csv", trajectory, g);
    out.files.push_back(out_dir / "trajectory_wgs84.csv");
    summary.trajectory_frames = static_cast<int>(trajectory.size());

    // 3. Landmarks (and an OpenStreetMap catalogue's streets, which name the topology's edges).
    std::vector<Street> streets;
    if (inputs.landmarks || !inputs.landmarks_path.empty()) {
      OsmLandmarkOptions osm;
      osm.radius_m = options.osm_radius_m;
      for (const FramePose& k : inputs.keyframes)
        osm.trajectory.push_back(g.MapToWgs84(k.world_from_camera.translation));
      std::vector<Landmark> catalogue = !inputs.landmarks ? ReadLandmarks(inputs.landmarks_path, osm)
                                        : IsOsmCatalogue(inputs.landmarks_path)
                                            ? KeepNearTrajectory(*inputs.landmarks, osm)
                                            : *inputs.landmarks;
      if (IsOsmCatalogue(inputs.landmarks_path)) streets = ReadStreetsOsm(inputs.landmarks_path, osm);
      MakeLandmarkNamesUnique(catalogue);
      out.landmarks = PlaceLandmarks(catalogue, g, keyframe_positions, options.landmarks);
      WriteLandmarksGeoJson(out_dir / "landmarks.geojson", out.landmarks, keyframe_positions,
                            options.landmarks.sigma_m);
      out.files.push_back(out_dir / "landmarks.geojson");
      summary.landmarks = static_cast<int>(out.landmarks.size());
      summary.landmarks_associated =
          static_cast<int>(std::count_if(out.landmarks.begin(), out.landmarks.end(),
                                         [](const PlacedLandmark& l) { return l.nearest_keyframe >= 0; }));
    }

    // 4. The topological map.
    out.topology = BuildTopologicalMap(keyframe_positions, out.landmarks, g, options.topology, streets);
    WriteTopologyFiles(out_dir, *out.topology);
    for (const char* name : {"topology.geojson", "topology.graphml", "topology.dot", "topology.json"}) {
      out.files.push_back(out_dir / name);
    }
    out.map_sections["topology"] = TopologyJsonString(*out.topology);
    GeoContext section{inputs.other_maps, out.landmarks, inputs.map_id, options.landmarks.sigma_m};
    section.maps.insert_or_assign(inputs.map_id, g);
    out.map_sections["geo"] = GeoSectionJson(section);
    summary.topology_nodes = static_cast<int>(out.topology->nodes.size());
    summary.topology_landmark_nodes = out.topology->NumLandmarkNodes();
    summary.topology_turn_nodes = out.topology->NumTurnNodes();
    summary.topology_edges = static_cast<int>(out.topology->edges.size());
    summary.topology_revisited_nodes = out.topology->NumRevisitedNodes();
  }

  // 5. Objects.
  if (!inputs.points.empty()) {
    std::optional<RoadScale> road_scale;
    if (!out.georeference && inputs.monocular && options.road_scale) {
      std::vector<Rigid3d> keyframe_poses;
      for (const FramePose& kf : inputs.keyframes) keyframe_poses.push_back(kf.world_from_camera);
      road_scale = EstimateRoadScale(keyframe_poses, inputs.points, *options.road_scale);
      if (road_scale) {
        spdlog::info(
            "objects: a map unit is {:.3f} m, from the camera's height above the road ({:.2f} m, {:.4f} "
            "map units over {} keyframes, spread {:.1f} %)",
            road_scale->metres_per_map_unit, options.road_scale->camera_height_m,
            road_scale->camera_height_map, road_scale->keyframes, 100.0 * road_scale->spread);
        summary.road_scale_keyframes = road_scale->keyframes;
        summary.road_scale_spread = road_scale->spread;
      } else {
        spdlog::warn(
            "objects: a monocular map without GPS, and too few road points beneath its keyframes for its "
            "scale: object radii and sizes are in map units, not metres");
      }
    }
    out.objects =
        BuildObjectMap(inputs.points, options.objects, out.georeference ? &*out.georeference : nullptr,
                       road_scale ? std::optional(road_scale->metres_per_map_unit) : std::nullopt);
    summary.objects_metres_per_map_unit = out.objects.metres_per_map_unit;
    summary.objects_scale_source = out.objects.scale_source;
    WriteObjectsJson(out_dir / "objects.json", out.objects, options.objects);
    out.files.push_back(out_dir / "objects.json");
    summary.objects = static_cast<int>(out.objects.objects.size());
    for (const SemanticObject& o : out.objects.objects)
      summary.objects_per_class[std::string(ClassKey(o.label))]++;
  }

  // 6. Plots.
  if (options.write_plots) WriteGeoPlots(inputs, trajectory, options, gps_plot, out_dir / "plots", out);
  return out;
}

std::string GeoSectionJson(const GeoContext& context) {
  json maps = json::array();
  for (const auto& [map_id, georeference] : context.maps) {
    maps.push_back({{"map", map_id}, {"georeference", json::parse(GeoreferenceToJson(georeference))}});
  }
  json root = {{"format", "semslam-geo"},
               {"version", 2},
               {"maps", maps},
               {"landmarks", json::parse(PlacedLandmarksToJson(context.landmarks))},
               {"landmarks_map", context.landmarks_map},
               {"sigma_m", context.sigma_m}};
  return root.dump();
}

GeoContext ParseGeoSection(const std::string& text, const fs::path& source, std::uint32_t single_map_id) {
  const auto fail = [&](const std::string& field, const std::string& message) {
    throw InputError(SourceLocation{source, 0}, field, message);
  };
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    fail("json", e.what());
  }
  if (!root.is_object() || root.value("format", std::string()) != "semslam-geo") {
    fail("format", "not a semslam geo section (expected \"format\": \"semslam-geo\")");
  }
  if (!root.contains("version") || !root["version"].is_number_integer()) fail("version", "missing");
  const int version = root["version"].get<int>();
  if (version != 1 && version != 2) fail("version", fmt::format("unsupported version {}", version));
  for (const char* key : {"landmarks", "sigma_m"}) {
    if (!root.contains(key)) fail(key, "missing");
  }
  if (!root["sigma_m"].is_number() || !(root["sigma_m"].get<double>() > 0))
    fail("sigma_m", "expected a positive number");
  GeoContext context;
  context.landmarks = PlacedLandmarksFromJson(root["landmarks"].dump(), source);
  context.sigma_m = root["sigma_m"].get<double>();
  if (version == 1) {
    if (!root.contains("georeference")) fail("georeference", "missing");
    context.maps.emplace(single_map_id, GeoreferenceFromJson(root["georeference"].dump(), source));
    context.landmarks_map = single_map_id;
    return context;
  }
  if (!root.contains("maps") || !root["maps"].is_array()) fail("maps", "expected an array");
  for (const json& entry : root["maps"]) {
    if (!entry.is_object() || !entry.contains("map") || !entry["map"].is_number_unsigned() ||
        !entry.contains("georeference")) {
      fail("maps", "each entry needs \"map\" (a map id) and \"georeference\"");
    }
    const auto map_id = entry["map"].get<std::uint32_t>();
    if (!context.maps.emplace(map_id, GeoreferenceFromJson(entry["georeference"].dump(), source)).second) {
      fail("maps", fmt::format("map {} is given twice", map_id));
    }
  }
  if (!root.contains("landmarks_map") || !root["landmarks_map"].is_number_unsigned())
    fail("landmarks_map", "expected a map id");
  context.landmarks_map = root["landmarks_map"].get<std::uint32_t>();
  return context;
}

GeoPose LocateInWorld(const Rigid3d& world_from_camera, const Georeference& g, const GeoContext& context,
                      bool with_landmarks, size_t max_landmarks) {
  const Eigen::Vector3d centre = world_from_camera.translation;
  GeoPose pose;
  pose.enu = g.MapToEnu(centre);
  pose.wgs84 = g.enu_frame.ToWgs84(pose.enu);
  const Eigen::Quaterniond enu_from_map_rotation =
      g.local ? g.local->keyframes()[g.local->NearestInMap(centre)].enu_from_map.rotation
              : g.enu_from_map.rotation;
  const Eigen::Vector3d forward =
      enu_from_map_rotation * (world_from_camera.rotation * Eigen::Vector3d::UnitZ());
  double bearing = std::atan2(forward.x(), forward.y()) * 180.0 / std::numbers::pi;
  if (bearing < 0) bearing += 360.0;
  pose.heading_deg = bearing;
  if (!with_landmarks) return pose;
  for (const NearLandmark& n :
       NearestLandmarks(centre, context.landmarks, g, context.sigma_m, max_landmarks)) {
    pose.nearest.push_back(
        {context.landmarks[static_cast<size_t>(n.landmark)].landmark.name, n.distance_m, n.membership});
  }
  return pose;
}

}  // namespace semslam
