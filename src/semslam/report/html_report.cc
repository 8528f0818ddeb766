#include "semslam/report/html_report.h"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <map>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <string_view>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/report/html_encoding.h"
#include "semslam/report/html_report_assets.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/semantic_outputs.h"

namespace semslam {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// ---------------------------------------------------------------------------------------------------------
// Reading the run folder.

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

// Typed, located access to a JSON document: absent and null members are "not there"; members of the wrong
// type are InputErrors naming the file and the field.
class JsonFields {
 public:
  explicit JsonFields(fs::path file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(std::string_view field, std::string_view message) const {
    if (field.empty()) throw InputError(SourceLocation{file_, 0}, message);
    throw InputError(SourceLocation{file_, 0}, field, message);
  }

  static const json* Find(const json& object, std::string_view key) {
    if (!object.is_object()) return nullptr;
    const auto it = object.find(key);
    if (it == object.end() || it->is_null()) return nullptr;
    return &*it;
  }
  std::optional<double> Number(const json& object, std::string_view key, std::string_view field) const {
    const json* value = Find(object, key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_number()) Fail(field, "expected a number");
    const double number = value->get<double>();
    if (!std::isfinite(number)) Fail(field, "not a finite number");
    return number;
  }
  std::optional<long long> Integer(const json& object, std::string_view key, std::string_view field) const {
    const json* value = Find(object, key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_number_integer()) Fail(field, "expected an integer");
    return value->get<long long>();
  }
  std::optional<std::string> String(const json& object, std::string_view key, std::string_view field) const {
    const json* value = Find(object, key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_string()) Fail(field, "expected a string");
    return value->get<std::string>();
  }
  std::optional<bool> Bool(const json& object, std::string_view key, std::string_view field) const {
    const json* value = Find(object, key);
    if (value == nullptr) return std::nullopt;
    if (!value->is_boolean()) Fail(field, "expected true or false");
    return value->get<bool>();
  }
  const json* Object(const json& object, std::string_view key, std::string_view field) const {
    const json* value = Find(object, key);
    if (value != nullptr && !value->is_object()) Fail(field, "expected an object");
    return value;
  }
  const json* Array(const json& object, std::string_view key, std::string_view field) const {
    const json* value = Find(object, key);
    if (value != nullptr && !value->is_array()) Fail(field, "expected an array");
    return value;
  }
  // A 3-vector of finite numbers.
  std::optional<Eigen::Vector3d> Vector3(const json& object, std::string_view key,
                                         std::string_view field) const {
    const json* value = Array(object, key, field);
    if (value == nullptr) return std::nullopt;
    if (value->size() != 3) Fail(field, "expected 3 numbers");
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
      const json& x = (*value)[static_cast<size_t>(i)];
      if (!x.is_number() || !std::isfinite(x.get<double>())) Fail(field, "expected 3 finite numbers");
      v[i] = x.get<double>();
    }
    return v;
  }

 private:
  fs::path file_;
};

struct ModuleTiming {
  std::string name;
  long long count = 0;
  double median_ms = 0.0;
  std::optional<double> mean_ms, p95_ms, max_ms, total_ms;
};

struct LandmarkRow {
  std::string name, category;
  std::optional<double> lat, lon;
  std::optional<Eigen::Vector3d> map_xyz;
  std::optional<long long> keyframe_id, frame_index;
  std::optional<double> keyframe_distance_m, membership, sigma_m;
  std::optional<double> error_m, horizontal_error_m;  // from run.json geo_evaluation
};

struct ObjectRow {
  long long id = 0;
  std::string class_name;
  long long points = 0;
  std::optional<Eigen::Vector3d> size_m, centroid_enu, centroid_map;
  std::optional<double> lat, lon, mean_confidence;
};

struct PlotImage {
  std::string name;  // file name
  std::string base64;
};

struct ReportInputs {
  fs::path run_dir;
  json run;
  std::optional<std::vector<ModuleTiming>> timing;
  std::optional<std::vector<SemanticPoint>> points;
  std::optional<Trajectory> trajectory, keyframes;
  std::optional<std::vector<LandmarkRow>> landmarks;
  std::optional<std::vector<ObjectRow>> objects;
  long long objects_total = 0;
  std::vector<PlotImage> plots;
  std::vector<std::string> notes;
};

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

std::vector<ObjectRow> ReadObjects(const fs::path& file, long long* total) {
  const json root = ParseJsonFile(file);
  const JsonFields f(file);
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
  *total = static_cast<long long>(rows.size());
  return rows;
}

bool IsPng(std::string_view bytes) {
  static constexpr std::string_view kSignature("\x89PNG\r\n\x1a\n", 8);
  return bytes.substr(0, kSignature.size()) == kSignature;
}

// The plots semslam writes, in the order a reader wants them, then any other PNG in plots/ by name.
constexpr std::array<std::pair<std::string_view, std::string_view>, 4> kKnownPlots = {{
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
  if (const fs::path file = run_dir / "objects.json"; Exists(file)) {
    in.objects = ReadObjects(file, &in.objects_total);
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

// ---------------------------------------------------------------------------------------------------------
// Formatting.

std::string Dash() { return "&mdash;"; }

std::string GroupThousands(long long value) {
  std::string digits = std::to_string(value < 0 ? -value : value);
  std::string out;
  for (size_t i = 0; i < digits.size(); ++i) {
    if (i > 0 && (digits.size() - i) % 3 == 0) out += "&#8239;";  // narrow no-break space
    out += digits[i];
  }
  return value < 0 ? "-" + out : out;
}

// Milliseconds with about three significant digits.
std::string FormatMs(double ms) {
  if (ms >= 1000.0) return GroupThousands(std::llround(ms));
  if (ms >= 100.0) return fmt::format("{:.0f}", ms);
  if (ms >= 10.0) return fmt::format("{:.1f}", ms);
  if (ms >= 1.0) return fmt::format("{:.2f}", ms);
  return fmt::format("{:.3f}", ms);
}

std::string FormatHz(double ms) {
  if (!(ms > 0.0)) return Dash();
  const double hz = 1000.0 / ms;
  if (hz >= 1000.0) return GroupThousands(std::llround(hz));
  if (hz >= 100.0) return fmt::format("{:.0f}", hz);
  if (hz >= 10.0) return fmt::format("{:.1f}", hz);
  return fmt::format("{:.2f}", hz);
}

std::string FormatPercent(double fraction) { return fmt::format("{:.1f}&nbsp;%", 100.0 * fraction); }

std::string FormatNumber(double value, int decimals) { return fmt::format("{:.{}f}", value, decimals); }

std::string FormatMetres(double metres) {
  if (std::abs(metres) >= 100.0) return fmt::format("{:.0f}&nbsp;m", metres);
  if (std::abs(metres) >= 10.0) return fmt::format("{:.1f}&nbsp;m", metres);
  return fmt::format("{:.2f}&nbsp;m", metres);
}

std::string Cell(const std::string& html, std::optional<double> sort_value = std::nullopt) {
  if (sort_value) return fmt::format("<td class=\"num\" data-v=\"{:.9g}\">{}</td>", *sort_value, html);
  return "<td>" + html + "</td>";
}

// ---------------------------------------------------------------------------------------------------------
// Sections.

struct Page {
  std::string body;
  std::vector<std::pair<std::string, std::string>> toc;  // id, title
  std::vector<std::string> sections;

  void Open(const std::string& id, const std::string& title) {
    toc.emplace_back(id, title);
    sections.push_back(id);
    body += fmt::format("<section id=\"{}\">\n<h2>{}</h2>\n", id, HtmlEscape(title));
  }
  void Close() { body += "</section>\n"; }
};

struct KeyValue {
  std::string key;
  std::string value_html;
};

void AppendKeyValueTable(std::string& html, const std::string& caption, const std::vector<KeyValue>& rows) {
  if (rows.empty()) return;
  html += "<table class=\"kv\">\n";
  if (!caption.empty()) html += "<caption>" + HtmlEscape(caption) + "</caption>\n";
  for (const KeyValue& row : rows) {
    html += "<tr><th scope=\"row\">" + HtmlEscape(row.key) + "</th><td>" + row.value_html + "</td></tr>\n";
  }
  html += "</table>\n";
}

void AppendSummary(Page& page, const ReportInputs& in) {
  const fs::path run_json = in.run_dir / "run.json";
  const JsonFields f(run_json);
  const json& run = in.run;
  page.Open("summary", "Summary");

  std::vector<KeyValue> rows;
  if (const auto sequence = f.String(run, "sequence", "sequence"))
    rows.push_back({"Sequence", HtmlEscape(*sequence)});
  if (const auto mode = f.String(run, "mode", "mode")) {
    rows.push_back({"Mode", *mode == "mono" ? "monocular" : HtmlEscape(*mode)});
  }
  const auto frames = f.Integer(run, "frames", "frames");
  const auto first_frame = f.Integer(run, "first_frame", "first_frame");
  if (frames) {
    std::string value = GroupThousands(*frames);
    if (first_frame) value += fmt::format(" (frames {}&ndash;{})", *first_frame, *first_frame + *frames - 1);
    rows.push_back({"Frames", value});
  }
  if (const auto tracked = f.Integer(run, "tracked", "tracked")) {
    std::string value = GroupThousands(*tracked);
    if (frames && *frames > 0) {
      value += " (" + FormatPercent(static_cast<double>(*tracked) / static_cast<double>(*frames)) + ")";
    }
    rows.push_back({"Frames tracked", value});
  }
  if (const auto v = f.Integer(run, "keyframes", "keyframes"))
    rows.push_back({"Keyframes", GroupThousands(*v)});
  if (const auto v = f.Integer(run, "points", "points")) rows.push_back({"Map points", GroupThousands(*v)});
  if (const auto v = f.Integer(run, "loops", "loops")) rows.push_back({"Loop closures", GroupThousands(*v)});
  if (const auto v = f.Integer(run, "relocalizations", "relocalizations")) {
    rows.push_back({"Relocalizations", GroupThousands(*v)});
  }
  if (const auto v = f.Integer(run, "resets", "resets"); v && *v > 0) {
    rows.push_back({"Map resets", GroupThousands(*v)});
  }
  if (const auto seconds = f.Number(run, "seconds", "seconds")) {
    std::string value = fmt::format("{:.1f}&nbsp;s", *seconds);
    if (frames && *seconds > 0) value += fmt::format(" ({:.1f} frames/s overall)", *frames / *seconds);
    rows.push_back({"Run time", value});
  }
  if (const auto v = f.Number(run, "peak_rss_mib", "peak_rss_mib")) {
    rows.push_back({"Peak memory", fmt::format("{:.0f}&nbsp;MiB", *v)});
  }
  if (const auto ate = f.Number(run, "ate_rmse", "ate_rmse")) {
    std::string value = FormatMetres(*ate) + " RMSE";
    std::vector<std::string> details;
    if (const auto alignment = f.String(run, "ate_alignment", "ate_alignment")) {
      const std::string name = *alignment == "sim3" ? "Sim(3)" : *alignment == "se3" ? "SE(3)" : *alignment;
      details.push_back(HtmlEscape(name) + " alignment");
    }
    if (const auto matched = f.Integer(run, "ate_matched", "ate_matched")) {
      details.push_back(GroupThousands(*matched) + " poses");
    }
    if (const auto length = f.Number(run, "path_length_m", "path_length_m"); length && *length > 0) {
      details.push_back(
          fmt::format("{:.2f}&nbsp;% of the {} path", 100.0 * *ate / *length, FormatMetres(*length)));
    }
    if (!details.empty()) {
      value += " (" + details[0];
      for (size_t i = 1; i < details.size(); ++i) value += ", " + details[i];
      value += ")";
    }
    rows.push_back({"Trajectory error (ATE)", value});
  }
  AppendKeyValueTable(page.body, "Run", rows);

  // Semantics.
  rows.clear();
  const json* segmentation = f.Object(run, "segmentation", "segmentation");
  if (segmentation != nullptr) {
    if (const auto s = f.String(*segmentation, "segmenter", "segmentation.segmenter")) {
      rows.push_back({"Segmenter", HtmlEscape(*s)});
    }
    if (const auto k = f.Integer(*segmentation, "segmented_keyframes", "segmentation.segmented_keyframes")) {
      std::string value = GroupThousands(*k) + " keyframes";
      if (const auto n = f.Integer(*segmentation, "segmented_frames", "segmentation.segmented_frames")) {
        value += ", " + GroupThousands(*n) + " frames";
      }
      const auto skipped = f.Integer(*segmentation, "skipped", "segmentation.skipped").value_or(0);
      const auto failed = f.Integer(*segmentation, "failed", "segmentation.failed").value_or(0);
      if (skipped > 0 || failed > 0) value += fmt::format(" ({} skipped, {} failed)", skipped, failed);
      rows.push_back({"Segmented", value});
    }
    if (const auto d = f.Bool(*segmentation, "exclude_dynamic", "segmentation.exclude_dynamic"); d && *d) {
      rows.push_back({"Dynamic classes", "kept out of tracking"});
    }
  }
  if (const auto accuracy = f.Number(run, "label_accuracy", "label_accuracy")) {
    std::string value = FormatPercent(*accuracy) + " of the map points labeled right";
    if (const json* evaluation = f.Object(run, "label_evaluation", "label_evaluation")) {
      if (const json* fused = f.Object(*evaluation, "fused_points", "label_evaluation.fused_points")) {
        if (const auto n = f.Integer(*fused, "evaluated", "label_evaluation.fused_points.evaluated")) {
          value += " (" + GroupThousands(*n) + " evaluated)";
        }
      }
      if (const json* single =
              f.Object(*evaluation, "single_frame_keypoints", "label_evaluation.single_frame_keypoints")) {
        if (const auto a =
                f.Number(*single, "accuracy", "label_evaluation.single_frame_keypoints.accuracy")) {
          value += "; single-frame segmentation at keypoints: " + FormatPercent(*a);
        }
      }
    }
    rows.push_back({"Label accuracy (fused)", value});
  }
  AppendKeyValueTable(page.body, "Semantics", rows);

  // GPS, landmarks, topology, objects.
  rows.clear();
  if (const json* geo = f.Object(run, "geo", "geo")) {
    const bool georeferenced = f.Bool(*geo, "georeferenced", "geo.georeferenced").value_or(false);
    if (georeferenced) {
      std::string value;
      const auto fixes = f.Integer(*geo, "gps_fixes", "geo.gps_fixes");
      const auto format = f.String(*geo, "gps_format", "geo.gps_format");
      if (fixes) value = GroupThousands(*fixes) + " fixes";
      if (format) value += " (" + HtmlEscape(*format) + ")";
      const auto samples = f.Integer(*geo, "gps_samples", "geo.gps_samples");
      const auto inliers = f.Integer(*geo, "gps_inliers", "geo.gps_inliers");
      if (samples) {
        value += fmt::format("; {} samples", GroupThousands(*samples));
        if (inliers) value += fmt::format(", {} inliers", GroupThousands(*inliers));
      }
      rows.push_back({"GPS", value});
      const bool fused = f.Bool(*geo, "fused", "geo.fused").value_or(false);
      std::string alignment;
      if (const auto r = f.Number(*geo, "single_sim3_rmse_m", "geo.single_sim3_rmse_m")) {
        alignment = "single similarity: " + FormatMetres(*r) + " RMSE";
      }
      if (const auto r = f.Number(*geo, "fused_rmse_m", "geo.fused_rmse_m"); r && fused) {
        alignment +=
            (alignment.empty() ? "" : "; ") + std::string("pose-graph fusion: ") + FormatMetres(*r) + " RMSE";
      }
      if (const auto s = f.Number(*geo, "metres_per_map_unit", "geo.metres_per_map_unit")) {
        alignment += fmt::format("{}{:.4g} m per map unit", alignment.empty() ? "" : "; ", *s);
      }
      if (!alignment.empty()) rows.push_back({"GPS alignment", alignment});
    } else {
      rows.push_back({"GPS", "not georeferenced"});
    }
    if (const auto n = f.Integer(*geo, "landmarks", "geo.landmarks"); n && *n > 0) {
      std::string value = GroupThousands(*n);
      if (const auto a = f.Integer(*geo, "landmarks_associated", "geo.landmarks_associated")) {
        value += fmt::format(", {} associated with a keyframe", GroupThousands(*a));
      }
      rows.push_back({"Landmarks", value});
    }
    if (const auto n = f.Integer(*geo, "topology_nodes", "geo.topology_nodes"); n && *n > 0) {
      std::string value = GroupThousands(*n) + " nodes";
      const auto landmark_nodes = f.Integer(*geo, "topology_landmark_nodes", "geo.topology_landmark_nodes");
      const auto turn_nodes = f.Integer(*geo, "topology_turn_nodes", "geo.topology_turn_nodes");
      const auto revisited = f.Integer(*geo, "topology_revisited_nodes", "geo.topology_revisited_nodes");
      if (landmark_nodes || turn_nodes) {
        value += fmt::format(" ({} landmark, {} turn", landmark_nodes.value_or(0), turn_nodes.value_or(0));
        if (revisited && *revisited > 0) value += fmt::format(", {} revisited", *revisited);
        value += ")";
      }
      if (const auto e = f.Integer(*geo, "topology_edges", "geo.topology_edges")) {
        value += ", " + GroupThousands(*e) + " edges";
      }
      rows.push_back({"Topological map", value});
    }
    if (const auto n = f.Integer(*geo, "objects", "geo.objects"); n && *n > 0) {
      rows.push_back({"Objects", GroupThousands(*n)});
    }
  }
  if (const json* evaluation = f.Object(run, "geo_evaluation", "geo_evaluation")) {
    const auto median =
        f.Number(*evaluation, "landmark_error_median_m", "geo_evaluation.landmark_error_median_m");
    const auto max = f.Number(*evaluation, "landmark_error_max_m", "geo_evaluation.landmark_error_max_m");
    if (median) {
      std::string value = "median " + FormatMetres(*median);
      if (max) value += ", max " + FormatMetres(*max);
      const auto hmedian = f.Number(*evaluation, "landmark_error_horizontal_median_m",
                                    "geo_evaluation.landmark_error_horizontal_median_m");
      if (hmedian) value += " (horizontal median " + FormatMetres(*hmedian) + ")";
      rows.push_back({"Landmark position error", value});
    }
    if (const auto r =
            f.Number(*evaluation, "trajectory_ate_rmse_m", "geo_evaluation.trajectory_ate_rmse_m")) {
      std::string value = FormatMetres(*r) + " RMSE";
      if (const auto m =
              f.Number(*evaluation, "trajectory_ate_max_m", "geo_evaluation.trajectory_ate_max_m")) {
        value += ", max " + FormatMetres(*m);
      }
      rows.push_back({"Trajectory error in ENU (no alignment)", value});
    }
  }
  AppendKeyValueTable(page.body, "GPS, landmarks and topology", rows);

  // Per-class counts and accuracies.
  const json* classes = f.Object(run, "classes", "classes");
  if (classes != nullptr) {
    const json* fused_classes = nullptr;
    const json* single_classes = nullptr;
    if (const json* evaluation = f.Object(run, "label_evaluation", "label_evaluation")) {
      if (const json* fused = f.Object(*evaluation, "fused_points", "label_evaluation.fused_points")) {
        fused_classes = f.Object(*fused, "per_class", "label_evaluation.fused_points.per_class");
      }
      if (const json* single =
              f.Object(*evaluation, "single_frame_keypoints", "label_evaluation.single_frame_keypoints")) {
        single_classes = f.Object(*single, "per_class", "label_evaluation.single_frame_keypoints.per_class");
      }
    }
    long long total = 0;
    std::vector<std::pair<int, long long>> counts;  // trainId (kNoLabel: unlabeled), count
    for (int id = 0; id <= kNumClasses; ++id) {
      const std::string key = id < kNumClasses ? std::string(ClassKey(id)) : "unlabeled";
      if (const auto n = f.Integer(*classes, key, "classes." + key); n && *n > 0) {
        counts.emplace_back(id < kNumClasses ? id : kNoLabel, *n);
        total += *n;
      }
    }
    if (!counts.empty()) {
      page.body +=
          "<table class=\"data sortable\">\n<caption>Map points per class</caption>\n<thead><tr>"
          "<th>class</th><th class=\"num\">points</th><th class=\"num\">share</th>"
          "<th class=\"num\">fused accuracy</th><th class=\"num\">single-frame "
          "accuracy</th></tr></thead>\n<tbody>\n";
      auto accuracy_cell = [&](const json* per_class, const std::string& key, const std::string& field) {
        if (per_class == nullptr) return Cell(Dash(), -1.0);
        const json* c = f.Object(*per_class, key, field + "." + key);
        if (c == nullptr) return Cell(Dash(), -1.0);
        const auto a = f.Number(*c, "accuracy", field + "." + key + ".accuracy");
        if (!a) return Cell(Dash(), -1.0);
        return Cell(FormatPercent(*a), *a);
      };
      for (const auto& [id, n] : counts) {
        const Rgb color = id == kNoLabel ? Rgb{150, 150, 150} : ClassColor(id);
        const std::string key = id == kNoLabel ? "unlabeled" : std::string(ClassKey(id));
        const std::string name = id == kNoLabel ? "unlabeled" : std::string(ClassName(id));
        page.body += fmt::format(
            "<tr><td><span class=\"swatch\" style=\"background:rgb({},{},{})\"></span>{}</td>{}{}{}{}</tr>\n",
            color.r, color.g, color.b, HtmlEscape(name), Cell(GroupThousands(n), static_cast<double>(n)),
            Cell(FormatPercent(static_cast<double>(n) / static_cast<double>(total)),
                 static_cast<double>(n) / static_cast<double>(total)),
            accuracy_cell(fused_classes, key, "label_evaluation.fused_points.per_class"),
            accuracy_cell(single_classes, key, "label_evaluation.single_frame_keypoints.per_class"));
      }
      page.body += "</tbody>\n</table>\n";
    }
  }
  page.Close();
}

const ModuleTiming* FindModule(const std::vector<ModuleTiming>& modules, std::string_view name) {
  for (const ModuleTiming& m : modules) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

void AppendTimeAnalysis(Page& page, const ReportInputs& in) {
  const JsonFields f(in.run_dir / "run.json");
  const std::vector<ModuleTiming> no_modules;
  const std::vector<ModuleTiming>& modules = in.timing ? *in.timing : no_modules;

  struct Row {
    std::string what, detail;
    std::optional<double> median_ms, p95_ms;
    std::optional<long long> count;
    std::string paper;
  };
  std::vector<Row> rows;
  // Semantic segmentation: timed by the segmentation worker (run.json), or a "segmentation" timing entry.
  {
    Row row{"Semantic segmentation", "per segmented frame, on the segmentation worker", {}, {}, {},
            "1.8 Hz (PSPNet-101)"};
    if (const ModuleTiming* m = FindModule(modules, "segmentation")) {
      row.median_ms = m->median_ms;
      row.p95_ms = m->p95_ms;
      row.count = m->count;
    } else if (const json* s = f.Object(in.run, "segmentation", "segmentation")) {
      row.median_ms = f.Number(*s, "median_ms", "segmentation.median_ms");
      if (row.median_ms) {
        const auto frames = f.Integer(*s, "segmented_frames", "segmentation.segmented_frames").value_or(0);
        const auto keyframes =
            f.Integer(*s, "segmented_keyframes", "segmentation.segmented_keyframes").value_or(0);
        row.count = std::max(frames, keyframes);
      }
    }
    if (const json* s = f.Object(in.run, "segmentation", "segmentation")) {
      if (const auto name = f.String(*s, "segmenter", "segmentation.segmenter")) {
        const std::string first_word = name->substr(0, name->find(' '));
        row.detail += "; " + first_word;
      }
    }
    rows.push_back(row);
  }
  // A module's row from its timing entry (the first of `names` that was timed).
  const auto module_row = [&](std::string what, std::string detail, std::string paper,
                              std::initializer_list<std::string_view> names) {
    Row row{std::move(what), std::move(detail), {}, {}, {}, std::move(paper)};
    for (const std::string_view name : names) {
      if (const ModuleTiming* m = FindModule(modules, name)) {
        row.median_ms = m->median_ms;
        row.p95_ms = m->p95_ms;
        row.count = m->count;
        break;
      }
    }
    rows.push_back(std::move(row));
  };
  module_row("Tracking", "per frame, tracking thread (ORB extraction, motion model, local map)",
             "15.1 Hz (ORB-SLAM2)", {"tracking"});
  module_row("Data association (label fusion)", "per segmented frame, labels fused into map points", "0.5 ms",
             {"label_fusion"});
  module_row("Local mapping", "per keyframe, local-mapping thread (triangulation, local BA, culling)", "",
             {"local_mapping"});
  module_row("Loop closing", "per keyframe, loop thread (detection; correction when a loop is found)", "",
             {"loop_closing", "loop_detection"});
  {
    Row row{"Whole system",
            "frames / run seconds (start-up and outputs included)",
            {},
            {},
            {},
            "&asymp;1.8 Hz (i7 + GTX 1080Ti)"};
    const auto frames = f.Integer(in.run, "frames", "frames");
    const auto seconds = f.Number(in.run, "seconds", "seconds");
    if (frames && seconds && *frames > 0 && *seconds > 0) {
      row.median_ms = 1000.0 * *seconds / static_cast<double>(*frames);
      row.count = *frames;
    }
    rows.push_back(row);
  }

  page.Open("time-analysis", "Time analysis (the paper's Table I, measured on this run)");
  page.body +=
      "<p>Median and 95th percentile of each module's time per call on this machine; the rate is "
      "1000&nbsp;/&nbsp;median, the calls per second the module sustains on its own thread. Segmentation, "
      "label fusion, local mapping and loop closing run beside tracking, on keyframes or segmented frames, "
      "so "
      "tracking never waits for them. The paper measured its system on an Intel Core i7 with an NVIDIA GTX "
      "1080Ti.</p>\n"
      "<table class=\"data\" id=\"table-i\">\n<thead><tr><th>module</th><th class=\"num\">median ms</th>"
      "<th class=\"num\">p95 ms</th><th class=\"num\">rate Hz</th><th class=\"num\">calls</th>"
      "<th>paper (Table I)</th></tr></thead>\n<tbody>\n";
  for (const Row& row : rows) {
    page.body += fmt::format(
        "<tr><td>{}<div class=\"detail\">{}</div></td>{}{}{}{}<td>{}</td></tr>\n", HtmlEscape(row.what),
        HtmlEscape(row.detail), row.median_ms ? Cell(FormatMs(*row.median_ms), *row.median_ms) : Cell(Dash()),
        row.p95_ms ? Cell(FormatMs(*row.p95_ms), *row.p95_ms) : Cell(Dash()),
        row.median_ms ? Cell(FormatHz(*row.median_ms), 1000.0 / *row.median_ms) : Cell(Dash()),
        row.count ? Cell(GroupThousands(*row.count), static_cast<double>(*row.count)) : Cell(Dash()),
        row.paper.empty() ? Dash() : row.paper);
  }
  page.body += "</tbody>\n</table>\n";
  page.Close();

  if (!in.timing || in.timing->empty()) return;
  std::vector<ModuleTiming> sorted = *in.timing;
  std::stable_sort(sorted.begin(), sorted.end(), [](const ModuleTiming& a, const ModuleTiming& b) {
    return a.total_ms.value_or(0.0) > b.total_ms.value_or(0.0);
  });
  double max_total = 0.0;
  for (const ModuleTiming& m : sorted) max_total = std::max(max_total, m.total_ms.value_or(0.0));
  page.Open("modules", "Every module");
  page.body +=
      "<p>From <code>timing.json</code>, by total time. Modules nest (tracking includes ORB extraction and "
      "pose optimization; local mapping includes local BA), so totals do not add up. Click a column to "
      "sort.</p>\n"
      "<table class=\"data sortable\" id=\"module-table\">\n<thead><tr><th>module</th><th "
      "class=\"num\">calls</th>"
      "<th class=\"num\">median ms</th><th class=\"num\">mean ms</th><th class=\"num\">p95 ms</th>"
      "<th class=\"num\">max ms</th><th class=\"num\">total ms</th><th class=\"num\">rate Hz</th>"
      "<th>share of the largest total</th></tr></thead>\n<tbody>\n";
  auto optional_ms = [](const std::optional<double>& v) { return v ? Cell(FormatMs(*v), *v) : Cell(Dash()); };
  for (const ModuleTiming& m : sorted) {
    const double share = max_total > 0 ? m.total_ms.value_or(0.0) / max_total : 0.0;
    page.body += fmt::format(
        "<tr><td><code>{}</code></td>{}{}{}{}{}{}{}<td><span class=\"bar\" "
        "style=\"width:{:.1f}%\"></span></td>"
        "</tr>\n",
        HtmlEscape(m.name), Cell(GroupThousands(m.count), static_cast<double>(m.count)),
        Cell(FormatMs(m.median_ms), m.median_ms), optional_ms(m.mean_ms), optional_ms(m.p95_ms),
        optional_ms(m.max_ms), optional_ms(m.total_ms),
        m.median_ms > 0 ? Cell(FormatHz(m.median_ms), 1000.0 / m.median_ms) : Cell(Dash()), 100.0 * share);
  }
  page.body += "</tbody>\n</table>\n";
  page.Close();
}

// ---------------------------------------------------------------------------------------------------------
// The 3D view's data.

void AppendFloat32(std::string& bytes, double value) {
  const auto bits = std::bit_cast<std::uint32_t>(static_cast<float>(value));
  for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<char>((bits >> (8 * k)) & 0xffu));  // little-endian
}

// Indices of a seeded random subset of `count` of `total` items, in increasing order.
std::vector<std::size_t> SampleIndices(std::size_t total, std::size_t count, std::uint64_t seed) {
  std::vector<std::size_t> indices(total);
  std::iota(indices.begin(), indices.end(), std::size_t{0});
  if (count >= total) return indices;
  std::mt19937_64 rng(seed);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = i + static_cast<std::size_t>(rng() % (total - i));
    std::swap(indices[i], indices[j]);
  }
  indices.resize(count);
  std::sort(indices.begin(), indices.end());
  return indices;
}

// Evenly spaced indices (first and last included).
std::vector<std::size_t> EvenIndices(std::size_t total, std::size_t count) {
  std::vector<std::size_t> indices;
  if (total <= count) {
    indices.resize(total);
    std::iota(indices.begin(), indices.end(), std::size_t{0});
    return indices;
  }
  for (std::size_t i = 0; i < count; ++i) {
    indices.push_back(static_cast<std::size_t>(std::llround(
        static_cast<double>(i) * static_cast<double>(total - 1) / static_cast<double>(count - 1))));
  }
  return indices;
}

int LabelKey(int label) { return IsValidTrainId(label) ? label : kNoLabel; }

double Percentile(std::vector<double> values, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

struct ViewData {
  json data;
  std::size_t points_shown = 0, trajectory_poses = 0;
};

ViewData BuildViewData(const ReportInputs& in, const HtmlReportOptions& options) {
  ViewData view;
  json& data = view.data;
  data["frame"] = "map";

  // Points: a seeded random subset, sorted by label so that a class is one contiguous range.
  std::array<long long, kNumClasses + 1> map_counts{};
  std::array<long long, kNumClasses + 1> shown_counts{};
  auto slot = [](int key) { return key == kNoLabel ? kNumClasses : key; };
  std::vector<std::size_t> chosen;
  if (in.points) {
    for (const SemanticPoint& p : *in.points) ++map_counts[static_cast<std::size_t>(slot(LabelKey(p.label)))];
    chosen = SampleIndices(in.points->size(), options.max_points, options.seed);
    std::stable_sort(chosen.begin(), chosen.end(), [&](std::size_t a, std::size_t b) {
      return slot(LabelKey((*in.points)[a].label)) < slot(LabelKey((*in.points)[b].label));
    });
    std::string positions, labels;
    positions.reserve(chosen.size() * 12);
    labels.reserve(chosen.size());
    json ranges = json::array();
    for (std::size_t i = 0; i < chosen.size(); ++i) {
      const SemanticPoint& p = (*in.points)[chosen[i]];
      const int key = LabelKey(p.label);
      for (int axis = 0; axis < 3; ++axis) AppendFloat32(positions, p.position[axis]);
      labels.push_back(static_cast<char>(key));
      ++shown_counts[static_cast<std::size_t>(slot(key))];
      if (ranges.empty() || ranges.back()[0].get<int>() != key) ranges.push_back({key, i, 0});
      ranges.back()[2] = ranges.back()[2].get<std::size_t>() + 1;
    }
    view.points_shown = chosen.size();
    data["points"] = {{"total", in.points->size()},
                      {"count", chosen.size()},
                      {"positions_b64", Base64Encode(positions)},
                      {"labels_b64", Base64Encode(labels)},
                      {"class_ranges", ranges}};
  }
  json classes = json::array();
  for (int slot_index = 0; slot_index <= kNumClasses; ++slot_index) {
    const bool none = slot_index == kNumClasses;
    const Rgb color = none ? Rgb{150, 150, 150} : ClassColor(slot_index);
    classes.push_back({{"id", none ? kNoLabel : slot_index},
                       {"name", none ? std::string("unlabeled") : std::string(ClassName(slot_index))},
                       {"color", {color.r, color.g, color.b}},
                       {"map_count", map_counts[static_cast<std::size_t>(slot_index)]},
                       {"shown", shown_counts[static_cast<std::size_t>(slot_index)]}});
  }
  data["classes"] = classes;

  Eigen::AlignedBox3d box;
  auto positions_b64 = [&](const Trajectory& trajectory, const std::vector<std::size_t>& indices) {
    std::string bytes;
    bytes.reserve(indices.size() * 12);
    for (const std::size_t i : indices) {
      const Eigen::Vector3d& t = trajectory[i].world_from_camera.translation;
      box.extend(t);
      for (int axis = 0; axis < 3; ++axis) AppendFloat32(bytes, t[axis]);
    }
    return Base64Encode(bytes);
  };
  if (in.trajectory) {
    const std::vector<std::size_t> indices = EvenIndices(in.trajectory->size(), options.max_trajectory_poses);
    view.trajectory_poses = indices.size();
    data["trajectory"] = {{"total", in.trajectory->size()},
                          {"count", indices.size()},
                          {"positions_b64", positions_b64(*in.trajectory, indices)}};
  }
  if (in.keyframes) {
    const std::vector<std::size_t> indices = EvenIndices(in.keyframes->size(), in.keyframes->size());
    data["keyframes"] = {{"total", in.keyframes->size()},
                         {"count", indices.size()},
                         {"positions_b64", positions_b64(*in.keyframes, indices)}};
  }
  json landmarks = json::array();
  if (in.landmarks) {
    for (const LandmarkRow& row : *in.landmarks) {
      if (!row.map_xyz) continue;
      box.extend(*row.map_xyz);
      landmarks.push_back(
          {{"name", row.name}, {"position", {(*row.map_xyz)[0], (*row.map_xyz)[1], (*row.map_xyz)[2]}}});
    }
  }
  data["landmarks"] = landmarks;

  // The initial view: the trajectory, the landmarks and the bulk of the points (2nd to 98th percentile per
  // axis, so that a few far points do not shrink everything else to a dot).
  if (!chosen.empty()) {
    Eigen::Vector3d low, high;
    for (int axis = 0; axis < 3; ++axis) {
      std::vector<double> values;
      values.reserve(chosen.size());
      for (const std::size_t i : chosen) values.push_back((*in.points)[i].position[axis]);
      low[axis] = Percentile(values, 0.02);
      high[axis] = Percentile(values, 0.98);
    }
    box.extend(low);
    box.extend(high);
  }
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 1.0;
  if (!box.isEmpty()) {
    center = box.center();
    radius = std::max(0.5 * box.diagonal().norm(), 1e-3);
  }
  data["view"] = {{"center", {center[0], center[1], center[2]}}, {"radius", radius}};
  return view;
}

void AppendMapView(Page& page, const ReportInputs& in, const ViewData& view) {
  page.Open("map3d", "Semantic map in 3D");
  page.body += fmt::format(
      "<p>Map frame (the first camera: x right, y down, z forward), shown with &minus;y up. {} of {} map "
      "points "
      "shown{}. Drag to rotate, wheel to zoom, shift-drag or right-drag to pan; click a class to hide or "
      "show "
      "it.</p>\n",
      GroupThousands(static_cast<long long>(view.points_shown)),
      GroupThousands(static_cast<long long>(in.points ? in.points->size() : 0)),
      in.points && view.points_shown < in.points->size() ? " (a random subset)" : "");
  page.body += R"HTML(<div class="viewer">
<div class="canvas-wrap" id="view-wrap"><canvas id="view-canvas"></canvas><canvas id="view-overlay"></canvas>
<div class="view-status" id="view-status">loading&hellip;</div></div>
<div class="view-side">
<div class="buttons">
<button type="button" id="view-reset">Reset view</button>
<button type="button" id="view-top">Top view</button>
<button type="button" id="view-background">Background</button>
</div>
<label class="slider">point size <input type="range" id="view-point-size" min="1" max="8" step="0.5" value="2"></label>
<div class="toggles">
<label><input type="checkbox" id="show-trajectory" checked> <span class="swatch" style="background:#00c8ff"></span>trajectory</label>
<label><input type="checkbox" id="show-keyframes" checked> <span class="swatch" style="background:#ff9f1a"></span>keyframes</label>
<label><input type="checkbox" id="show-landmarks" checked> <span class="swatch" style="background:#ff4fd8"></span>landmarks</label>
</div>
<div class="buttons"><button type="button" id="classes-all">All classes</button>
<button type="button" id="classes-none">No class</button></div>
<table class="legend" id="legend"><thead><tr><th>class</th><th class="num">map</th><th class="num">shown</th></tr></thead>
<tbody></tbody></table>
</div>
</div>
)HTML";
  page.Close();
}

void AppendPlots(Page& page, const ReportInputs& in) {
  if (in.plots.empty()) return;
  page.Open("plots", "Plots");
  page.body += "<div class=\"plots\">\n";
  for (const PlotImage& plot : in.plots) {
    const std::string caption = PlotCaption(plot.name);
    page.body += fmt::format(
        "<figure><img src=\"data:image/png;base64,{}\" alt=\"{}\" data-name=\"{}\"><figcaption>{} "
        "<code>plots/{}</code></figcaption></figure>\n",
        plot.base64, HtmlEscape(caption), HtmlEscape(plot.name), HtmlEscape(caption), HtmlEscape(plot.name));
  }
  page.body += "</div>\n";
  page.Close();
}

std::string OptionalCell(const std::optional<double>& value, const std::string& html) {
  return value ? Cell(html, *value) : Cell(Dash(), -1.0);
}

void AppendLandmarks(Page& page, const ReportInputs& in) {
  if (!in.landmarks || in.landmarks->empty()) return;
  page.Open("landmarks", "Landmarks");
  page.body +=
      "<p>From <code>landmarks.geojson</code>: each landmark of the catalogue, the keyframe nearest to it "
      "and "
      "that keyframe's fuzzy membership m = exp(&minus;d&sup2;&nbsp;/&nbsp;2&sigma;&sup2;) (the paper's "
      "&sect;III-D). The error is the placed position against the synthetic city's truth, when known.</p>\n"
      "<table class=\"data sortable\" id=\"landmark-table\">\n<thead><tr><th>name</th><th>category</th>"
      "<th class=\"num\">lat</th><th class=\"num\">lon</th><th class=\"num\">nearest keyframe</th>"
      "<th class=\"num\">frame</th><th class=\"num\">distance</th><th class=\"num\">membership</th>"
      "<th class=\"num\">error</th></tr></thead>\n<tbody>\n";
  for (const LandmarkRow& row : *in.landmarks) {
    const auto as_double = [](const std::optional<long long>& v) -> std::optional<double> {
      return v ? std::optional<double>(static_cast<double>(*v)) : std::nullopt;
    };
    std::string error_html;
    if (row.error_m) {
      error_html = FormatMetres(*row.error_m);
      if (row.horizontal_error_m) error_html += " (" + FormatMetres(*row.horizontal_error_m) + " horiz.)";
    }
    page.body += fmt::format(
        "<tr><td>{}</td><td>{}</td>{}{}{}{}{}{}{}</tr>\n", HtmlEscape(row.name), HtmlEscape(row.category),
        OptionalCell(row.lat, row.lat ? FormatNumber(*row.lat, 6) : ""),
        OptionalCell(row.lon, row.lon ? FormatNumber(*row.lon, 6) : ""),
        OptionalCell(as_double(row.keyframe_id), row.keyframe_id ? std::to_string(*row.keyframe_id) : ""),
        OptionalCell(as_double(row.frame_index), row.frame_index ? std::to_string(*row.frame_index) : ""),
        OptionalCell(row.keyframe_distance_m,
                     row.keyframe_distance_m ? FormatMetres(*row.keyframe_distance_m) : ""),
        OptionalCell(row.membership, row.membership ? FormatNumber(*row.membership, 3) : ""),
        OptionalCell(row.error_m, error_html));
  }
  page.body += "</tbody>\n</table>\n";
  page.Close();
}

std::string FormatVector(const Eigen::Vector3d& v, int decimals, std::string_view separator) {
  return fmt::format("{:.{}f}{}{:.{}f}{}{:.{}f}", v[0], decimals, separator, v[1], decimals, separator, v[2],
                     decimals);
}

void AppendObjects(Page& page, const ReportInputs& in, const HtmlReportOptions& options) {
  if (!in.objects) return;
  page.Open("objects", "Objects");
  std::map<std::string, int> per_class;
  for (const ObjectRow& row : *in.objects) ++per_class[row.class_name];
  std::string counts;
  for (const auto& [name, n] : per_class) {
    counts += fmt::format("{}{} {}", counts.empty() ? "" : ", ", n, HtmlEscape(name));
  }
  page.body += fmt::format(
      "<p>From <code>objects.json</code>: labeled map points clustered per class. {} objects{}{}.</p>\n",
      GroupThousands(in.objects_total), counts.empty() ? "" : ": ", counts);
  if (in.objects->empty()) {
    page.Close();
    return;
  }
  const bool enu = std::any_of(in.objects->begin(), in.objects->end(),
                               [](const ObjectRow& row) { return row.centroid_enu.has_value(); });
  page.body += fmt::format(
      "<table class=\"data sortable\" id=\"object-table\">\n<thead><tr><th "
      "class=\"num\">id</th><th>class</th>"
      "<th class=\"num\">points</th><th>size (m)</th><th>centroid ({})</th><th class=\"num\">lat</th>"
      "<th class=\"num\">lon</th><th class=\"num\">confidence</th></tr></thead>\n<tbody>\n",
      enu ? "ENU, m" : "map frame");
  const std::size_t rows = std::min(in.objects->size(), options.max_table_rows);
  for (std::size_t i = 0; i < rows; ++i) {
    const ObjectRow& row = (*in.objects)[i];
    const std::optional<Eigen::Vector3d>& centroid = enu ? row.centroid_enu : row.centroid_map;
    page.body += fmt::format(
        "<tr>{}<td>{}</td>{}<td>{}</td><td>{}</td>{}{}{}</tr>\n",
        Cell(std::to_string(row.id), static_cast<double>(row.id)), HtmlEscape(row.class_name),
        Cell(GroupThousands(row.points), static_cast<double>(row.points)),
        row.size_m ? FormatVector(*row.size_m, 1, " &times; ") : Dash(),
        centroid ? FormatVector(*centroid, enu ? 1 : 3, ", ") : Dash(),
        OptionalCell(row.lat, row.lat ? FormatNumber(*row.lat, 6) : ""),
        OptionalCell(row.lon, row.lon ? FormatNumber(*row.lon, 6) : ""),
        OptionalCell(row.mean_confidence, row.mean_confidence ? FormatNumber(*row.mean_confidence, 3) : ""));
  }
  page.body += "</tbody>\n</table>\n";
  if (rows < in.objects->size()) {
    page.body += fmt::format("<p class=\"detail\">{} more objects are in <code>objects.json</code>.</p>\n",
                             GroupThousands(static_cast<long long>(in.objects->size() - rows)));
  }
  page.Close();
}

void AppendNotes(Page& page, const std::vector<std::string>& notes) {
  if (notes.empty()) return;
  page.Open("notes", "Left out");
  page.body += "<ul>\n";
  for (const std::string& note : notes) page.body += "<li>" + HtmlEscape(note) + "</li>\n";
  page.body += "</ul>\n";
  page.Close();
}

std::string Title(const ReportInputs& in, const HtmlReportOptions& options) {
  if (!options.title.empty()) return options.title;
  std::string name;
  if (const json* sequence = JsonFields::Find(in.run, "sequence"); sequence && sequence->is_string()) {
    name = fs::path(sequence->get<std::string>()).filename().string();
  }
  if (name.empty()) name = fs::absolute(in.run_dir).filename().string();
  return "semslam report: " + name;
}

}  // namespace

void HtmlReportOptions::Check() const {
  Require(max_trajectory_poses >= 2, "html report max_trajectory_poses must be at least 2");
  Require(max_plot_bytes > 0, "html report max_plot_bytes must be positive");
}

HtmlReportResult WriteHtmlReport(const fs::path& run_dir, const HtmlReportOptions& options) {
  options.Check();
  ReportInputs in = ReadInputs(run_dir, options);

  Page page;
  AppendSummary(page, in);
  AppendTimeAnalysis(page, in);  // without timing.json, Table I still has segmentation and the whole system
  const bool has_view = in.points || in.trajectory || in.keyframes;
  ViewData view;
  if (has_view) {
    view = BuildViewData(in, options);
    AppendMapView(page, in, view);
  } else {
    in.notes.push_back("no semantic_map.ply, trajectory.tum or keyframes.tum: the 3D view left out");
  }
  if (!options.embed_plots) in.notes.push_back("plots not embedded (embed_plots is off)");
  AppendPlots(page, in);
  AppendLandmarks(page, in);
  AppendObjects(page, in, options);
  AppendNotes(page, in.notes);

  const std::string title = Title(in, options);
  std::string html;
  html.reserve(page.body.size() + 64 * 1024);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<meta name=\"generator\" content=\"semslam\">\n";
  html += "<title>" + HtmlEscape(title) + "</title>\n<style>\n";
  html += HtmlReportCss();
  html += "</style>\n</head>\n<body>\n<header>\n<h1>" + HtmlEscape(title) + "</h1>\n<nav>";
  for (const auto& [id, section_title] : page.toc) {
    html += fmt::format("<a href=\"#{}\">{}</a>", id,
                        HtmlEscape(section_title.substr(0, section_title.find(" ("))));
  }
  html += "</nav>\n</header>\n<main>\n<div id=\"js-errors\" hidden></div>\n";
  html += page.body;
  html += "</main>\n<footer>Written by semslam from <code>" +
          HtmlEscape(fs::absolute(run_dir).lexically_normal().string()) +
          "</code>. One self-contained file: it needs no network.</footer>\n";
  if (has_view) {
    html += "<script type=\"application/json\" id=\"semslam-data\">";
    html += JsonForScriptElement(view.data.dump(-1, ' ', false, json::error_handler_t::replace));
    html += "</script>\n";
  }
  html += "<script>\n";
  html += HtmlReportScript();
  html += "</script>\n</body>\n</html>\n";

  HtmlReportResult result;
  result.path = run_dir / "report.html";
  WriteFileAtomically(result.path, html);
  result.bytes = html.size();
  result.map_points = in.points ? in.points->size() : 0;
  result.points_shown = view.points_shown;
  result.trajectory_poses = view.trajectory_poses;
  result.sections = page.sections;
  result.notes = in.notes;
  return result;
}

}  // namespace semslam
