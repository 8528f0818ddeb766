#include "semslam/system/demo.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/timing.h"
#include "semslam/sim/dataset_writer.h"
#include "semslam/system/localizer.h"
#include "semslam/system/run_metadata.h"
#include "semslam/system/sequence_runner.h"
#include "semslam/topology/routing.h"

namespace semslam {
namespace {

void RenderDrive(const DemoOptions& options, int frames, std::uint64_t traffic_seed,
                 const std::filesystem::path& out) {
  sim::SynthOptions synth = sim::PresetOptions("default");
  synth.city.seed = options.seed;
  synth.city.traffic_seed = traffic_seed;
  synth.route.frames = frames;
  const sim::SyntheticCity city(synth);
  spdlog::info("demo: rendering {} frames into {}", frames, out.string());
  sim::DatasetOptions dataset;
  dataset.progress = options.show_progress;
  dataset.overwrite = true;  // the demo's own folder
  sim::WriteDataset(city, out, dataset);
}

}  // namespace

void DemoOptions::Check() const {
  Require(!output.empty(), "demo: --out must not be empty");
  Require(frames >= 100, "demo: --frames must be at least 100");
  Require(second_drive_frames >= 50, "demo: the second drive needs at least 50 frames");
  Require(ParseSensorMode(mode).has_value(), "demo: --mode must be mono or stereo");
}

DemoSummary RunDemo(const DemoOptions& options) {
  options.Check();
  Stopwatch watch;
  const std::filesystem::path city = options.output / "city";
  const std::filesystem::path drive2 = options.output / "drive2";
  RenderDrive(options, options.frames, options.seed, city);
  RenderDrive(options, std::min(options.second_drive_frames, options.frames), options.seed + 1000, drive2);

  RunOptions run;
  run.sequence = city;
  run.output = options.output / "run";
  run.slam.mode = *ParseSensorMode(options.mode);  // checked by DemoOptions::Check
  run.slam.pacing = options.pacing;
  run.segmenter = options.segmenter;
  run.gps = city / "oxts";
  run.landmarks = city / "landmarks.csv";
  run.show_progress = options.show_progress;
  run.provenance = options.provenance;
  run.overwrite = true;  // the demo's own folder: a second demo replaces the first
  spdlog::info("demo: SLAM over the city -> {}", run.output.string());
  const RunSummary run_summary = RunSequence(run);

  LocalizeOptions localize;
  localize.map = run.output / "map.semslam";
  localize.sequence = drive2;
  localize.output = options.output / "localize";
  localize.slam.mode = run.slam.mode;
  localize.slam.pacing = Pacing::kFast;
  localize.show_progress = options.show_progress;
  localize.overwrite = true;
  spdlog::info("demo: a second drive relocalized against the map without GPS -> {}",
               localize.output.string());
  const LocalizeSummary localize_summary = LocalizeSequence(localize);

  DemoSummary summary;
  summary.ate_rmse = run_summary.ate_rmse;
  summary.label_accuracy = run_summary.label_accuracy;
  summary.localized_within_1m = localize_summary.within_1m;
  summary.nearest_landmark_right = localize_summary.nearest_landmark_right;
  const nlohmann::json run_json = ReadJsonFile(run.output / "run.json");
  summary.path_length_m = run_json.value("path_length_m", 0.0);

  // A route between the first and the last landmark of the topological map that the drive passed (a short
  // drive leaves some too far from its trajectory for a node).
  nlohmann::json route_json = nullptr;
  if (std::filesystem::exists(run.output / "topology.json")) {
    const TopologicalMap topology = ReadTopologyJson(run.output / "topology.json");
    std::vector<std::string> names;
    for (const TopoLandmark& landmark : topology.landmarks) {
      if (landmark.node >= 0) names.push_back(landmark.name);
    }
    if (names.size() < 2) spdlog::info("demo: fewer than two landmarks along the drive, no route");
    if (names.size() >= 2) {
      const Route route = FindRoute(topology, names.front(), names.back());
      WriteRouteGeoJson(options.output / "route.geojson", topology, route);
      summary.route_from = names.front();
      summary.route_to = names.back();
      summary.route_length_m = route.length_m;
      nlohmann::json steps = nlohmann::json::array();
      for (const RouteStep& step : route.steps) steps.push_back(step.text);
      route_json = {
          {"from", names.front()}, {"to", names.back()}, {"length_m", route.length_m}, {"steps", steps}};
    }
  }
  summary.seconds = watch.ElapsedSeconds();
  const nlohmann::json demo = {
      {"city", city.string()},
      {"run", run.output.string()},
      {"localize", localize.output.string()},
      {"mode", options.mode},
      {"frames", options.frames},
      {"ate_rmse", summary.ate_rmse},
      {"path_length_m", summary.path_length_m},
      {"ate_percent_of_path",
       summary.path_length_m > 0 ? 100.0 * summary.ate_rmse / summary.path_length_m : -1.0},
      {"label_accuracy", summary.label_accuracy},
      {"geo_evaluation", run_json.value("geo_evaluation", nlohmann::json(nullptr))},
      {"localized_within_1m", summary.localized_within_1m},
      {"nearest_landmark_right", summary.nearest_landmark_right},
      {"route", route_json},
      {"report", (run.output / "report.html").string()},
      {"seconds", summary.seconds}};
  WriteFileAtomically(options.output / "demo.json", demo.dump(2) + "\n");
  return summary;
}

}  // namespace semslam
