#pragma once
// The run report: one self-contained HTML file (no network, no external scripts) that a person opens in a
// browser after `semslam run` / `semslam demo`. It reads what the run wrote into its output folder:
//
//   run.json            required: the summary table (frames, tracking, map, ATE, labels, GPS, landmarks)
//   timing.json         the paper's Table I "time analysis" measured on this run, and every module's timing
//   semantic_map.ply    the interactive 3D view: points in the Cityscapes palette (a seeded random subset of
//   trajectory.tum      at most max_points), the camera trajectory and the keyframes, one toggle per class
//   keyframes.tum
//   landmarks.geojson   landmark markers in the 3D view and the landmark table
//   objects.json        the object table
//   georeference.json   the 3D view in ENU, north up
//   plots/*.png         embedded as base64 PNG
//
// and writes run_dir/report.html atomically. A missing optional input leaves its section out (the report says
// which); a missing or malformed run.json, or a malformed optional input, is an InputError naming the file.
//
// The page holds one <script type="application/json" id="semslam-data"> element with what the viewer needs:
// {"points": {"count", "total", "positions_b64" (float32 little-endian x y z per point, map frame),
// "labels_b64" (uint8 trainId, 255 = none; points sorted by label), "class_ranges"}, "trajectory",
// "keyframes", "landmarks", "classes", "view", "frame", "units"}, positions in the display frame: ENU (x east,
// y north, z up, metres) when the run folder has georeference.json, else the level map frame (x right, y
// forward of the first camera, z up). The 3D view uses WebGL and falls back to a 2D canvas; it opens on a
// top view, north (or the first camera's forward) up, with a grid.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace semslam {

struct HtmlReportOptions {
  std::string title;                          // default: "semslam: <dataset>/<sequence>, <run folder>"
  std::size_t max_points = 200'000;           // map points in the 3D view (0: trajectory only)
  std::size_t max_trajectory_poses = 20'000;  // camera positions of the trajectory line (evenly subsampled)
  std::size_t max_keyframes = 300;            // keyframe markers (evenly thinned on long runs)
  std::size_t max_table_rows = 1000;          // rows of the object table (the rest are counted, not listed)
  bool embed_plots = true;
  std::uintmax_t max_plot_bytes = 8u << 20;  // larger PNGs are left out (and named in the report)
  std::uint64_t seed = 1;                    // of the point subset, so that a report is reproducible

  void Check() const;  // throws InvalidArgument
};

struct HtmlReportResult {
  std::filesystem::path path;         // run_dir/report.html
  std::uintmax_t bytes = 0;           // its size
  std::size_t map_points = 0;         // points in semantic_map.ply
  std::size_t points_shown = 0;       // of them, in the 3D view
  std::size_t trajectory_poses = 0;   // in the 3D view
  std::size_t keyframes_shown = 0;    // in the 3D view
  std::vector<std::string> sections;  // element ids of the sections written, in page order
  std::vector<std::string> notes;     // inputs left out, and why
};

// Throws InputError (a missing or malformed run.json; a malformed optional input), InvalidArgument (bad
// options) or std::runtime_error (the report cannot be written).
HtmlReportResult WriteHtmlReport(const std::filesystem::path& run_dir, const HtmlReportOptions& options = {});

}  // namespace semslam
