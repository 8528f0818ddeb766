#pragma once
// The HTML report's parts (report/ internal): what it reads from the run folder, the page being written, and
// the sections. html_report.cc puts them together; see html_report.h.

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/geometry/sim3.h"
#include "semslam/geometry/trajectory.h"
#include "semslam/report/html_report.h"
#include "semslam/semantics/semantic_outputs.h"

namespace semslam::html_report {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string ReadBytes(const fs::path& file);
json ParseJsonFile(const fs::path& file);

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
  // objects.json's scale: `scale_source` (georeference, road or map; empty in files before it) and
  // `metres_per_map_unit`.
  std::string objects_scale_source;
  std::optional<double> objects_metres_per_map_unit;
  std::vector<PlotImage> plots;
  std::vector<std::string> notes;
  std::optional<Sim3d> enu_from_map;  // georeference.json: the 3D view is then ENU, north up, metres
};


// Reads the run folder (run.json required; the rest optional, noted when missing).
ReportInputs ReadInputs(const fs::path& run_dir, const HtmlReportOptions& options);
std::string PlotCaption(std::string_view name);

// ---- Formatting.
std::string Dash();
std::string GroupThousands(long long value);
std::string FormatMs(double ms);
std::string FormatHz(double ms);
std::string FormatPercent(double fraction);
std::string FormatNumber(double value, int decimals);
std::string FormatMetres(double metres);
std::string Cell(const std::string& html, std::optional<double> sort_value = std::nullopt);
std::string OptionalCell(const std::optional<double>& value, const std::string& html);

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

void AppendKeyValueTable(std::string& html, const std::string& caption, const std::vector<KeyValue>& rows);

// ---- Sections.
void AppendSummary(Page& page, const ReportInputs& in);
void AppendProvenance(Page& page, const ReportInputs& in);
void AppendTimeAnalysis(Page& page, const ReportInputs& in);

struct ViewData {
  json data;
  std::size_t points_shown = 0, trajectory_poses = 0, keyframes_shown = 0;
};
ViewData BuildViewData(const ReportInputs& in, const HtmlReportOptions& options);
void AppendMapView(Page& page, const ReportInputs& in, const ViewData& view);

}  // namespace semslam::html_report
