// semslam report RUN_DIR: rebuilds report.html from what a run wrote into its folder (run.json, timing.json,
// trajectories, the semantic map, landmarks, objects, plots), e.g. after a newer semslam changed the report.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "commands.h"
#include "semslam/report/html_report.h"

namespace semslam::cli {

void AddReportCommand(CLI::App& app) {
  auto run_dir = std::make_shared<std::string>();
  auto title = std::make_shared<std::string>();
  auto max_points = std::make_shared<size_t>(HtmlReportOptions{}.max_points);
  auto* cmd = app.add_subcommand("report", "Rebuild report.html from a run folder");
  cmd->add_option("run_dir", *run_dir, "Folder written by semslam run (with run.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--title", *title, "Page title (default: the sequence and the run folder)");
  cmd->add_option("--max-points", *max_points, "Map points in the 3D view (a seeded random subset)")
      ->capture_default_str();
  cmd->callback([=] {
    HtmlReportOptions options;
    options.title = *title;
    options.max_points = *max_points;
    const HtmlReportResult report = WriteHtmlReport(*run_dir, options);
    spdlog::info("report: {} ({} of {} map points shown, {} bytes)", report.path.string(), report.points_shown,
                 report.map_points, report.bytes);
  });
}

}  // namespace semslam::cli
