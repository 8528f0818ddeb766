// Table I of the report: the time each module takes, against the frame rate of the input.

#include <fmt/format.h>

#include <algorithm>

#include "semslam/report/html_encoding.h"
#include "semslam/report/html_report_internal.h"

namespace semslam::html_report {

namespace {

const ModuleTiming* FindModule(const std::vector<ModuleTiming>& modules, std::string_view name) {
  for (const ModuleTiming& m : modules) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

}  // namespace

void AppendTimeAnalysis(Page& page, const ReportInputs& in) {
  const JsonFields f(in.run_dir / "run.json");
  const std::vector<ModuleTiming> no_modules;
  const std::vector<ModuleTiming>& modules = in.timing ? *in.timing : no_modules;

  struct Row {
    std::string what, detail;
    std::optional<double> median_ms, p95_ms;
    std::optional<long long> count;
    std::string paper;
    std::optional<double> mean_ms;  // the whole system's run seconds / frames
  };
  std::vector<Row> rows;
  // Semantic segmentation: timed by the segmentation worker (run.json), or a "segmentation" timing entry.
  {
    Row row{"Semantic segmentation", "per segmented frame, on the segmentation worker", {}, {}, {},
            "1.8 Hz (PSPNet-101)"};
    if (const ModuleTiming* m = FindModule(modules, "segmentation")) {
      row.median_ms = m->median_ms;
      row.p95_ms = m->p95_ms;
      row.mean_ms = m->mean_ms;
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
        row.mean_ms = m->mean_ms;
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
    // The whole system per frame: the run loop's "frame" timing (loading, tracking, waiting for the camera's
    // rate when pacing is realtime); the mean includes start-up, the final optimization and the outputs.
    std::string pacing;
    if (const json* config = f.Object(in.run, "config", "config")) {
      pacing = f.String(*config, "pacing", "config.pacing").value_or("");
    }
    const std::string waits = pacing == "realtime" ? ", waiting for the camera's rate (pacing realtime)"
                              : pacing == "synchronous"
                                  ? ", waiting for mapping after each keyframe (pacing synchronous)"
                              : pacing.empty() ? ""
                                               : " (pacing " + pacing + ")";
    Row row{"Whole system",
            "per frame: loading, tracking" + waits +
                "; mean: run seconds / frames, start-up and outputs included",
            {},
            {},
            {},
            "&asymp;1.8 Hz (i7 + GTX 1080Ti)"};
    if (const ModuleTiming* m = FindModule(modules, "frame")) {
      row.median_ms = m->median_ms;
      row.p95_ms = m->p95_ms;
      row.count = m->count;
    }
    const auto frames = f.Integer(in.run, "frames", "frames");
    const auto seconds = f.Number(in.run, "seconds", "seconds");
    if (frames && seconds && *frames > 0 && *seconds > 0) {
      row.mean_ms = 1000.0 * *seconds / static_cast<double>(*frames);
      if (!row.count) row.count = *frames;
    }
    rows.push_back(row);
  }

  page.Open("time-analysis", "Time analysis (the paper's Table I, measured on this run)");
  page.body +=
      "<p>Median, 95th percentile and mean of each module's time per call on this machine; the rate is "
      "1000&nbsp;/&nbsp;median, the calls per second the module sustains on its own thread (for the whole "
      "system, 1000&nbsp;/&nbsp;mean: the frames per second of the run, start to end). Segmentation, "
      "label fusion, local mapping and loop closing run beside tracking, on keyframes or segmented frames, "
      "so "
      "tracking never waits for them. The paper measured its system on an Intel Core i7 with an NVIDIA GTX "
      "1080Ti.</p>\n"
      "<table class=\"data\" id=\"table-i\">\n<thead><tr><th>module</th><th class=\"num\">median ms</th>"
      "<th class=\"num\">p95 ms</th><th class=\"num\">mean ms</th><th class=\"num\">rate Hz</th>"
      "<th class=\"num\">calls</th>"
      "<th>paper (Table I)</th></tr></thead>\n<tbody>\n";
  for (const Row& row : rows) {
    // The rate of a module on its own thread is 1000 / median; the whole system's, its frames per second.
    const bool whole = row.what == "Whole system";
    const std::optional<double> rate_ms = whole && row.mean_ms ? row.mean_ms : row.median_ms;
    page.body += fmt::format(
        "<tr><td>{}<div class=\"detail\">{}</div></td>{}{}{}{}{}<td>{}</td></tr>\n", HtmlEscape(row.what),
        HtmlEscape(row.detail), row.median_ms ? Cell(FormatMs(*row.median_ms), *row.median_ms) : Cell(Dash()),
        row.p95_ms ? Cell(FormatMs(*row.p95_ms), *row.p95_ms) : Cell(Dash()),
        row.mean_ms ? Cell(FormatMs(*row.mean_ms), *row.mean_ms) : Cell(Dash()),
        rate_ms ? Cell(FormatHz(*rate_ms), 1000.0 / *rate_ms) : Cell(Dash()),
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

}  // namespace semslam::html_report
