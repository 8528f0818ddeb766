#include "semslam/report/html_report.h"

#include <fmt/format.h>

#include <algorithm>
#include <map>

#include "semslam/core/atomic_file.h"
#include "semslam/report/html_encoding.h"
#include "semslam/report/html_report_assets.h"
#include "semslam/report/html_report_internal.h"

namespace semslam {
namespace html_report {

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
  // Sizes are metres only where the map's scale is known (objects_json.cc).
  const bool map_units = in.objects_scale_source == "map";
  std::string scale;
  if (in.objects_scale_source == "georeference") {
    scale = " Sizes in metres, by the GPS.";
  } else if (in.objects_scale_source == "road" && in.objects_metres_per_map_unit) {
    scale = fmt::format(" Sizes in metres: a map unit is {} m, from the camera's height above the road.",
                        FormatNumber(*in.objects_metres_per_map_unit, 2));
  } else if (map_units) {
    scale =
        " Sizes in map units: metres for a stereo map; a monocular map without GPS or road labels has no "
        "scale.";
  }
  page.body += fmt::format(
      "<p>From <code>objects.json</code>: labeled map points clustered per class. {} objects{}{}.{}</p>\n",
      GroupThousands(in.objects_total), counts.empty() ? "" : ": ", counts, scale);
  if (in.objects->empty()) {
    page.Close();
    return;
  }
  const bool enu = std::any_of(in.objects->begin(), in.objects->end(),
                               [](const ObjectRow& row) { return row.centroid_enu.has_value(); });
  page.body += fmt::format(
      "<table class=\"data sortable\" id=\"object-table\">\n<thead><tr><th "
      "class=\"num\">id</th><th>class</th>"
      "<th class=\"num\">points</th><th>size ({})</th><th>centroid ({})</th><th class=\"num\">lat</th>"
      "<th class=\"num\">lon</th><th class=\"num\">confidence</th></tr></thead>\n<tbody>\n",
      map_units ? "map units" : "m", enu ? "ENU, m" : "map frame");
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

// "KITTI 00" names a sequence less well than the folders around it: the dataset folder and the sequence
// (".../city/sequences/00" -> "city/00"), then the run folder ("semslam: city/00, run").
std::string SequenceLabel(const fs::path& sequence) {
  fs::path p = sequence.lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  const std::string name = p.filename().string();
  const fs::path parent = p.parent_path();
  if (parent.filename() == "sequences" && !parent.parent_path().filename().empty()) {
    return parent.parent_path().filename().string() + "/" + name;
  }
  if (!parent.filename().empty()) return parent.filename().string() + "/" + name;
  return name;
}

std::string Title(const ReportInputs& in, const HtmlReportOptions& options) {
  if (!options.title.empty()) return options.title;
  std::string name;
  if (const json* sequence = JsonFields::Find(in.run, "sequence"); sequence && sequence->is_string()) {
    name = SequenceLabel(sequence->get<std::string>());
  }
  const std::string run = fs::absolute(in.run_dir).lexically_normal().filename().string();
  if (name.empty()) return "semslam report: " + run;
  return "semslam: " + name + (run.empty() ? "" : ", " + run);
}


}  // namespace html_report

void HtmlReportOptions::Check() const {
  Require(max_trajectory_poses >= 2, "html report max_trajectory_poses must be at least 2");
  Require(max_plot_bytes > 0, "html report max_plot_bytes must be positive");
  Require(max_keyframes >= 2, "html report max_keyframes must be at least 2");
}

HtmlReportResult WriteHtmlReport(const std::filesystem::path& run_dir, const HtmlReportOptions& options) {
  using namespace html_report;  // NOLINT: the report's parts
  options.Check();
  ReportInputs in = ReadInputs(run_dir, options);

  Page page;
  AppendSummary(page, in);
  AppendProvenance(page, in);
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
  result.keyframes_shown = view.keyframes_shown;
  result.sections = page.sections;
  result.notes = in.notes;
  return result;
}

}  // namespace semslam