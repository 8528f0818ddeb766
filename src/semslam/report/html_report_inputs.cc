#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <fstream>
#include <sstream>

#include "semslam/core/error.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/report/html_encoding.h"
#include "semslam/report/html_report_internal.h"

namespace semslam::html_report {

std::string ReadBytes(const fs::path& file) {
  std::ifstream stream(file, std::ios::binary);
  if (!stream) throw InputError(file, "cannot open the file");
  std::ostringstream buffer;
  buffer << stream.rdbuf();
  if (stream.bad()) throw InputError(file, "cannot read the file");
  return buffer.str();
}

json ParseJsonFile(const fs::path& file) {
  try {
    return json::parse(ReadBytes(file));
  } catch (const json::parse_error& e) {
    throw InputError(SourceLocation{file, 0}, "json", e.what());
  }
}

std::vector<ModuleTiming> ReadTiming(const fs::path& file) {
  const json root = ParseJsonFile(file);
  const JsonFields f(file);
  if (!root.is_object()) f.Fail("", "expected an object of modules");
  std::vector<ModuleTiming> modules;
  for (const auto& [name, entry] : root.items()) {
    if (!entry.is_object()) f.Fail(name, "expected an object");
    ModuleTiming m;
    m.name = name;
    const auto count = f.Integer(entry, "count", name + ".count");
    const auto median = f.Number(entry, "median_ms", name + ".median_ms");
    if (!count) f.Fail(name + ".count", "missing");
    if (!median) f.Fail(name + ".median_ms", "missing");
    m.count = *count;
    m.median_ms = *median;
    m.mean_ms = f.Number(entry, "mean_ms", name + ".mean_ms");
    m.p95_ms = f.Number(entry, "p95_ms", name + ".p95_ms");
    m.max_ms = f.Number(entry, "max_ms", name + ".max_ms");
    m.total_ms = f.Number(entry, "total_ms", name + ".total_ms");
    modules.push_back(std::move(m));
  }
  return modules;
}

std::vector<LandmarkRow> ReadLandmarks(const fs::path& file) {
  const json root = ParseJsonFile(file);
  const JsonFields f(file);
  const json* features = f.Array(root, "features", "features");
  if (features == nullptr) f.Fail("features", "missing: not a GeoJSON FeatureCollection");
  std::vector<LandmarkRow> rows;
  for (size_t i = 0; i < features->size(); ++i) {
    const json& feature = (*features)[i];
    const std::string field = fmt::format("features[{}]", i);
    const json* properties = f.Object(feature, "properties", field + ".properties");
    if (properties == nullptr) continue;
    LandmarkRow row;
    row.name = f.String(*properties, "name", field + ".properties.name").value_or("");
    row.category = f.String(*properties, "category", field + ".properties.category").value_or("");
    row.map_xyz = f.Vector3(*properties, "map_xyz", field + ".properties.map_xyz");
    row.membership = f.Number(*properties, "membership", field + ".properties.membership");
    row.sigma_m = f.Number(*properties, "sigma_m", field + ".properties.sigma_m");
    if (const json* nearest =
            f.Object(*properties, "nearest_keyframe", field + ".properties.nearest_keyframe")) {
      const std::string nk = field + ".properties.nearest_keyframe";
      row.keyframe_id = f.Integer(*nearest, "keyframe_id", nk + ".keyframe_id");
      row.frame_index = f.Integer(*nearest, "frame_index", nk + ".frame_index");
      row.keyframe_distance_m = f.Number(*nearest, "distance_m", nk + ".distance_m");
    }
    if (const json* geometry = f.Object(feature, "geometry", field + ".geometry")) {
      if (const json* coordinates = f.Array(*geometry, "coordinates", field + ".geometry.coordinates")) {
        if (coordinates->size() >= 2 && (*coordinates)[0].is_number() && (*coordinates)[1].is_number()) {
          row.lon = (*coordinates)[0].get<double>();
          row.lat = (*coordinates)[1].get<double>();
        } else {
          f.Fail(field + ".geometry.coordinates", "expected [lon, lat(, alt)]");
        }
      }
    }
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<ObjectRow> ReadObjects(const fs::path& file, ReportInputs& in) {
  const json root = ParseJsonFile(file);
  const JsonFields f(file);
  in.objects_scale_source = f.String(root, "scale_source", "scale_source").value_or("");
  in.objects_metres_per_map_unit = f.Number(root, "metres_per_map_unit", "metres_per_map_unit");
  const json* objects = f.Array(root, "objects", "objects");
  if (objects == nullptr) f.Fail("objects", "missing");
  std::vector<ObjectRow> rows;
  for (size_t i = 0; i < objects->size(); ++i) {
    const json& object = (*objects)[i];
    const std::string field = fmt::format("objects[{}]", i);
    ObjectRow row;
    row.id = f.Integer(object, "id", field + ".id").value_or(static_cast<long long>(i));
    row.class_name = f.String(object, "class", field + ".class").value_or("");
    row.points = f.Integer(object, "num_points", field + ".num_points").value_or(0);
    row.size_m = f.Vector3(object, "size_m", field + ".size_m");
    row.centroid_enu = f.Vector3(object, "centroid_enu", field + ".centroid_enu");
    row.centroid_map = f.Vector3(object, "centroid_map", field + ".centroid_map");
    row.mean_confidence = f.Number(object, "mean_confidence", field + ".mean_confidence");
    if (const json* wgs84 = f.Object(object, "centroid_wgs84", field + ".centroid_wgs84")) {
      row.lat = f.Number(*wgs84, "lat", field + ".centroid_wgs84.lat");
      row.lon = f.Number(*wgs84, "lon", field + ".centroid_wgs84.lon");
    }
    rows.push_back(std::move(row));
  }
  in.objects_total = static_cast<long long>(rows.size());
  return rows;
}

bool IsPng(std::string_view bytes) {
  static constexpr std::string_view kSignature("\x89PNG\r\n\x1a\n", 8);
  return bytes.substr(0, kSignature.size()) == kSignature;
}

// The plots semslam writes, in the order a reader wants them, then any other PNG in plots/ by name.
constexpr std::array<std::pair<std::string_view, std::string_view>, 7> kKnownPlots = {{
    {"trajectory.png", "The trajectory from above, against the ground truth when the sequence has one"},
    {"ate.png", "Absolute trajectory error along the drive (as evo_ape draws it)"},
    {"rpe.png", "Relative pose error between consecutive frames along the drive (as evo_rpe draws it)"},
    {"gps.png", "GPS fixes and the SLAM trajectory transformed into ENU (the paper's Fig. 2)"},
    {"topology.png", "Topological map: landmark and turn nodes, edges along the driven trajectory (Fig. 3)"},
    {"semantic_map.png", "Semantic map, top view, Cityscapes palette"},
    {"membership.png", "Fuzzy landmark membership m(x, y) with the landmarks and the trajectory"},
}};

std::string PlotCaption(std::string_view name) {
  for (const auto& [file, caption] : kKnownPlots) {
    if (file == name) return std::string(caption);
  }
  return std::string(name);
}

std::vector<fs::path> PlotFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code error;
  if (!fs::is_directory(dir, error)) return files;
  for (const auto& [file, caption] : kKnownPlots) {
    if (fs::is_regular_file(dir / file, error)) files.push_back(dir / file);
  }
  std::vector<fs::path> others;
  for (const auto& entry : fs::directory_iterator(dir, error)) {
    const fs::path& p = entry.path();
    if (!entry.is_regular_file(error) || p.extension() != ".png") continue;
    const std::string name = p.filename().string();
    if (std::none_of(kKnownPlots.begin(), kKnownPlots.end(),
                     [&](const auto& k) { return k.first == name; })) {
      others.push_back(p);
    }
  }
  std::sort(others.begin(), others.end());
  files.insert(files.end(), others.begin(), others.end());
  return files;
}

bool Exists(const fs::path& file) {
  std::error_code error;
  return fs::is_regular_file(file, error);
}

ReportInputs ReadInputs(const fs::path& run_dir, const HtmlReportOptions& options) {
  ReportInputs in;
  in.run_dir = run_dir;
  const fs::path run_json = run_dir / "run.json";
  if (!Exists(run_json)) {
    throw InputError(run_json, "missing: the report needs the run summary that `semslam run` writes");
  }
  in.run = ParseJsonFile(run_json);
  if (!in.run.is_object()) JsonFields(run_json).Fail("", "expected a JSON object");

  auto note_missing = [&](std::string_view file, std::string_view what) {
    in.notes.push_back(fmt::format("{} not found: {} left out", file, what));
  };
  if (const fs::path file = run_dir / "timing.json"; Exists(file)) {
    in.timing = ReadTiming(file);
  } else {
    note_missing("timing.json", "the module timings");
  }
  if (const fs::path file = run_dir / "semantic_map.ply"; Exists(file)) {
    in.points = ReadSemanticPly(file);
  } else {
    note_missing("semantic_map.ply", "the map points of the 3D view");
  }
  if (const fs::path file = run_dir / "trajectory.tum"; Exists(file)) {
    in.trajectory = ReadTumTrajectory(file);
  } else {
    note_missing("trajectory.tum", "the trajectory of the 3D view");
  }
  if (const fs::path file = run_dir / "keyframes.tum"; Exists(file)) {
    in.keyframes = ReadTumTrajectory(file);
  } else {
    note_missing("keyframes.tum", "the keyframes of the 3D view");
  }
  if (const fs::path file = run_dir / "landmarks.geojson"; Exists(file)) {
    in.landmarks = ReadLandmarks(file);
    const JsonFields f(run_json);
    if (const json* evaluation = f.Object(in.run, "geo_evaluation", "geo_evaluation")) {
      if (const json* errors = f.Array(*evaluation, "landmark_errors", "geo_evaluation.landmark_errors")) {
        for (size_t i = 0; i < errors->size(); ++i) {
          const std::string field = fmt::format("geo_evaluation.landmark_errors[{}]", i);
          const auto name = f.String((*errors)[i], "name", field + ".name");
          for (LandmarkRow& row : *in.landmarks) {
            if (!name || row.name != *name) continue;
            row.error_m = f.Number((*errors)[i], "error_m", field + ".error_m");
            row.horizontal_error_m = f.Number((*errors)[i], "horizontal_m", field + ".horizontal_m");
          }
        }
      }
    }
  }
  if (const fs::path file = run_dir / "georeference.json"; Exists(file)) {
    // The global similarity only: the 3D view's north-up frame (local corrections are a few metres at most).
    const json root = ParseJsonFile(file);
    const JsonFields f(file);
    const json* sim = f.Object(root, "enu_from_map", "enu_from_map");
    if (sim == nullptr) f.Fail("enu_from_map", "missing");
    const auto scale = f.Number(*sim, "scale", "enu_from_map.scale");
    const auto translation = f.Vector3(*sim, "translation", "enu_from_map.translation");
    const json* rotation = f.Array(*sim, "rotation_wxyz", "enu_from_map.rotation_wxyz");
    if (!scale || !(*scale > 0)) f.Fail("enu_from_map.scale", "expected a positive number");
    if (!translation) f.Fail("enu_from_map.translation", "missing");
    if (rotation == nullptr || rotation->size() != 4) f.Fail("enu_from_map.rotation_wxyz", "expected 4 numbers");
    double q[4];
    for (size_t i = 0; i < 4; ++i) {
      if (!(*rotation)[i].is_number()) f.Fail("enu_from_map.rotation_wxyz", "expected 4 numbers");
      q[i] = (*rotation)[i].get<double>();
    }
    const Eigen::Quaterniond quaternion(q[0], q[1], q[2], q[3]);
    if (!(std::abs(quaternion.norm() - 1.0) < 1e-3)) f.Fail("enu_from_map.rotation_wxyz", "not a unit quaternion");
    in.enu_from_map = Sim3d(*scale, quaternion.normalized(), *translation);
  }
  if (const fs::path file = run_dir / "objects.json"; Exists(file)) {
    in.objects = ReadObjects(file, in);
  }
  if (options.embed_plots) {
    for (const fs::path& file : PlotFiles(run_dir / "plots")) {
      std::error_code error;
      const std::uintmax_t size = fs::file_size(file, error);
      if (!error && size > options.max_plot_bytes) {
        in.notes.push_back(fmt::format("plots/{}: {} bytes, more than max_plot_bytes ({}): left out",
                                       file.filename().string(), size, options.max_plot_bytes));
        continue;
      }
      const std::string bytes = ReadBytes(file);
      if (!IsPng(bytes)) throw InputError(file, "not a PNG image");
      in.plots.push_back({file.filename().string(), Base64Encode(bytes)});
    }
  }
  return in;
}

}  // namespace semslam::html_report
