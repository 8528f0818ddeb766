#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <initializer_list>

#include "semslam/report/class_colors.h"
#include "semslam/report/html_encoding.h"
#include "semslam/report/html_report_internal.h"
#include "semslam/semantics/class_table.h"

namespace semslam::html_report {

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

std::string Cell(const std::string& html, std::optional<double> sort_value) {
  if (sort_value) return fmt::format("<td class=\"num\" data-v=\"{:.9g}\">{}</td>", *sort_value, html);
  return "<td>" + html + "</td>";
}

// ---------------------------------------------------------------------------------------------------------
// Sections.

void AppendKeyValueTable(std::string& html, const std::string& caption, const std::vector<KeyValue>& rows) {
  if (rows.empty()) return;
  html += "<table class=\"kv\">\n";
  if (!caption.empty()) html += "<caption>" + HtmlEscape(caption) + "</caption>\n";
  for (const KeyValue& row : rows) {
    html += "<tr><th scope=\"row\">" + HtmlEscape(row.key) + "</th><td>" + row.value_html + "</td></tr>\n";
  }
  html += "</table>\n";
}

namespace {

// The run's table: frames, tracking, map, camera, time, memory and trajectory error.
std::vector<KeyValue> RunRows(const JsonFields& f, const json& run) {
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
  if (const json* refinements = f.Array(run, "intrinsics_refinement", "intrinsics_refinement")) {
    // The final BA's self-calibration, per monocular map (atlas_outputs.h).
    for (const json& r : *refinements) {
      const auto map_id = f.Integer(r, "map", "intrinsics_refinement.map");
      const json* nominal = f.Object(r, "nominal", "intrinsics_refinement.nominal");
      const json* refined = f.Object(r, "refined", "intrinsics_refinement.refined");
      if (!map_id || nominal == nullptr || refined == nullptr) continue;
      const auto fx0 = f.Number(*nominal, "fx", "intrinsics_refinement.nominal.fx");
      const auto fx = f.Number(*refined, "fx", "intrinsics_refinement.refined.fx");
      const auto k1 = f.Number(*refined, "k1", "intrinsics_refinement.refined.k1");
      if (!fx0 || !fx || !k1) continue;
      const bool accepted = f.Bool(r, "accepted", "intrinsics_refinement.accepted").value_or(false);
      std::string value =
          accepted ? fmt::format("refined: f {:.1f} &rarr; {:.1f}&nbsp;px, k1 {:.4f}", *fx0, *fx, *k1)
                   : fmt::format("as given (f {:.1f}&nbsp;px)", *fx0);
      if (!accepted) {
        if (const auto reason = f.String(r, "reason", "intrinsics_refinement.reason")) {
          value += ": " + HtmlEscape(*reason);
        }
      }
      rows.push_back({refinements->size() > 1 ? fmt::format("Camera, map {}", *map_id) : "Camera", value});
    }
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
  return rows;
}

// The segmentation and the map labels' accuracy.
std::vector<KeyValue> SemanticRows(const JsonFields& f, const json& run) {
  std::vector<KeyValue> rows;
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
    // The headline (semantic_evaluation.h, formats.md): 3D, against the surface each point lies on with the
    // map placed in the world by one alignment, when the truth has depth; else 2D, against the truth at the
    // point's keypoints. The kinder figures follow it.
    std::string value;
    const json* evaluation = f.Object(run, "label_evaluation", "label_evaluation");
    if (const auto a3 = f.Number(run, "label_accuracy_3d", "label_accuracy_3d")) {
      value = FormatPercent(*accuracy) +
              " of the map points carry the class of the surface they lie on (3D, the map placed by one "
              "alignment";
      const json* surface =
          evaluation ? f.Object(*evaluation, "surface_points", "label_evaluation.surface_points") : nullptr;
      if (const auto n = surface
                             ? f.Integer(*surface, "evaluated", "label_evaluation.surface_points.evaluated")
                             : std::nullopt) {
        value += ", " + GroupThousands(*n) + " evaluated";
      }
      value += "); by each keyframe's own pose: " + FormatPercent(*a3);
      if (const auto a2 = f.Number(run, "label_accuracy_2d", "label_accuracy_2d")) {
        value += "; the class at their keypoints (2D): " + FormatPercent(*a2);
      }
    } else {
      value = FormatPercent(*accuracy) + " of the map points labeled right";
    }
    if (evaluation) {
      if (const json* fused = f.Object(*evaluation, "fused_points", "label_evaluation.fused_points")) {
        if (const auto n = f.Integer(*fused, "evaluated", "label_evaluation.fused_points.evaluated")) {
          value += " (" + GroupThousands(*n) + " evaluated in 2D)";
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
  return rows;
}

// GPS, landmarks, topology and objects.
std::vector<KeyValue> GeoRows(const JsonFields& f, const json& run) {
  std::vector<KeyValue> rows;
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
  return rows;
}

// Map points per class, with the fused and single-frame accuracies.
void AppendClassTable(std::string& html, const JsonFields& f, const json& run) {
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
    // The classes present (at least 0.5 % of the labeled points, as the plots and the 3D view list them), in
    // their display colours, commonest first; the rest and the unlabeled points in one "other" row.
    long long total = 0;
    std::array<long long, kNumClasses> class_counts{};
    long long unlabeled = 0;
    for (int id = 0; id <= kNumClasses; ++id) {
      const std::string key = id < kNumClasses ? std::string(ClassKey(id)) : "unlabeled";
      if (const auto n = f.Integer(*classes, key, "classes." + key); n && *n > 0) {
        (id < kNumClasses ? class_counts[static_cast<size_t>(id)] : unlabeled) = *n;
        total += *n;
      }
    }
    const ClassDisplay display = MakeClassDisplay(class_counts);
    std::vector<std::pair<int, long long>> counts;  // trainId (kNoLabel: other classes, unlabeled), count
    long long other = unlabeled;
    int other_classes = 0;
    for (int id = 0; id < kNumClasses; ++id) {
      const long long n = class_counts[static_cast<size_t>(id)];
      if (display.listed[static_cast<size_t>(id)]) {
        counts.emplace_back(id, n);
      } else if (n > 0) {
        other += n;
        ++other_classes;
      }
    }
    std::stable_sort(counts.begin(), counts.end(),
                     [](const auto& a, const auto& b) { return a.second > b.second; });
    if (other > 0) counts.emplace_back(kNoLabel, other);
    if (!counts.empty()) {
      html +=
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
        const Rgb color = id == kNoLabel ? display.other : display.color[static_cast<size_t>(id)];
        const std::string key = id == kNoLabel ? "unlabeled" : std::string(ClassKey(id));
        const std::string name =
            id == kNoLabel ? (other_classes > 0 ? fmt::format("{} other classes, unlabeled", other_classes)
                                                : std::string("unlabeled"))
                           : std::string(ClassName(id));
        html += fmt::format(
            "<tr><td><span class=\"swatch\" style=\"background:rgb({},{},{})\"></span>{}</td>{}{}{}{}</tr>\n",
            color.r, color.g, color.b, HtmlEscape(name), Cell(GroupThousands(n), static_cast<double>(n)),
            Cell(FormatPercent(static_cast<double>(n) / static_cast<double>(total)),
                 static_cast<double>(n) / static_cast<double>(total)),
            accuracy_cell(fused_classes, key, "label_evaluation.fused_points.per_class"),
            accuracy_cell(single_classes, key, "label_evaluation.single_frame_keypoints.per_class"));
      }
      html += "</tbody>\n</table>\n";
    }
  }
}

}  // namespace

void AppendSummary(Page& page, const ReportInputs& in) {
  const JsonFields f(in.run_dir / "run.json");
  page.Open("summary", "Summary");
  AppendKeyValueTable(page.body, "Run", RunRows(f, in.run));
  AppendKeyValueTable(page.body, "Semantics", SemanticRows(f, in.run));
  AppendKeyValueTable(page.body, "GPS, landmarks and topology", GeoRows(f, in.run));
  AppendClassTable(page.body, f, in.run);
  page.Close();
}

void AppendProvenance(Page& page, const ReportInputs& in) {
  const JsonFields f(in.run_dir / "run.json");
  const json* provenance = f.Object(in.run, "provenance", "provenance");
  const json* config = f.Object(in.run, "config", "config");
  if (provenance == nullptr && config == nullptr) return;
  page.Open("provenance", "How this run was made");
  std::vector<KeyValue> rows;
  if (provenance != nullptr) {
    if (const auto v = f.String(*provenance, "command_line", "provenance.command_line"))
      rows.push_back({"Command", "<code>" + HtmlEscape(*v) + "</code>"});
    std::string version =
        HtmlEscape(f.String(*provenance, "version", "provenance.version").value_or("unknown"));
    if (const auto commit = f.String(*provenance, "commit", "provenance.commit"))
      version += ", commit <code>" + HtmlEscape(*commit) + "</code>";
    if (const auto type = f.String(*provenance, "build_type", "provenance.build_type");
        type && !type->empty())
      version += ", " + HtmlEscape(*type) + " build";
    rows.push_back({"semslam", version});
    if (const auto v = f.String(*provenance, "date", "provenance.date"))
      rows.push_back({"Date (UTC)", HtmlEscape(*v)});
    if (const auto v = f.Integer(*provenance, "host_cores", "provenance.host_cores"))
      rows.push_back({"Host", fmt::format("{} cores", *v)});
  }
  if (config != nullptr) {
    if (const auto v = f.String(*config, "sequence", "config.sequence"))
      rows.push_back({"Sequence", "<code>" + HtmlEscape(*v) + "</code>"});
    if (const json* frames = f.Array(*config, "frames", "config.frames"); frames && frames->size() == 2 &&
                                                                          (*frames)[0].is_number_integer() &&
                                                                          (*frames)[1].is_number_integer()) {
      rows.push_back(
          {"Frames", fmt::format("{}:{}", (*frames)[0].get<long long>(), (*frames)[1].get<long long>())});
    }
    for (const auto& [key, label] :
         std::initializer_list<std::pair<const char*, const char*>>{{"mode", "Mode"},
                                                                    {"pacing", "Pacing"},
                                                                    {"segmenter", "Segmenter"},
                                                                    {"gps", "GPS log"},
                                                                    {"landmarks", "Landmarks"},
                                                                    {"map_in", "Starting map"},
                                                                    {"vocabulary", "Vocabulary"}}) {
      if (const auto v = f.String(*config, key, std::string("config.") + key); v && !v->empty())
        rows.push_back({label, HtmlEscape(*v)});
    }
    if (const auto v = f.Integer(*config, "gps_every", "config.gps_every");
        v && f.String(*config, "gps", "config.gps").value_or("") != "")
      rows.push_back({"GPS sampling", fmt::format("one fix every {} frames", *v)});
  }
  AppendKeyValueTable(page.body, "", rows);
  if (config != nullptr) {
    if (const json* slam = f.Object(*config, "slam", "config.slam")) {
      page.body +=
          "<details><summary>Every SLAM option used (as <code>config.yaml</code>, which "
          "<code>--config</code> "
          "reads)</summary>\n<table class=\"kv\">\n";
      for (const auto& [section, fields] : slam->items()) {
        if (!fields.is_object()) continue;
        for (const auto& [key, value] : fields.items()) {
          page.body += "<tr><th scope=\"row\">" + HtmlEscape(section + "." + key) + "</th><td><code>" +
                       HtmlEscape(value.dump()) + "</code></td></tr>\n";
        }
      }
      page.body += "</table>\n</details>\n";
    }
  }
  page.Close();
}

}  // namespace semslam::html_report
