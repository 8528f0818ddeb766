#pragma once
// `semslam demo`: the whole pipeline on the built-in synthetic city, every output written.
//
//   OUT/city/       the rendered town and drive (semslam synth): images, labels, depth, poses, GPS, landmarks
//   OUT/run/        semslam run, monocular, with truth-noisy segmentation, GPS and landmarks: trajectories,
//                   map.semslam, semantic_map.ply, landmarks, topology, objects, plots, report.html, run.json
//   OUT/drive2/     a second drive through the same town (other parked cars), without GPS
//   OUT/localize/   that drive relocalized against the saved map: poses in WGS84 and nearest landmarks
//   OUT/route.geojson and OUT/demo.json: a route between two landmarks and a summary of every figure

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "semslam/system/run_metadata.h"
#include "semslam/system/slam_system.h"

namespace semslam {

struct DemoOptions {
  std::filesystem::path output = "out/demo";
  int frames = 1200;  // the main drive (1200 frames hold a loop)
  int second_drive_frames = 300;
  std::uint64_t seed = 1;     // town and route
  std::string mode = "mono";  // mono or stereo
  Pacing pacing = Pacing::kRealtime;
  std::string segmenter = "truth-noisy:0.25";
  bool show_progress = true;
  RunProvenance provenance;  // recorded in run/run.json

  void Check() const;
};

struct DemoSummary {
  double ate_rmse = -1.0;
  double path_length_m = 0.0;
  double label_accuracy = -1.0;
  double localized_within_1m = -1.0;
  double nearest_landmark_right = -1.0;
  std::string route_from, route_to;
  double route_length_m = 0.0;
  double seconds = 0.0;
};

DemoSummary RunDemo(const DemoOptions& options);

}  // namespace semslam
