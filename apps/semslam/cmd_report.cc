// semslam report RUN_DIR: rebuilds report.html from what a run wrote into its folder (run.json, timing.json,
// trajectories, the semantic map, landmarks, objects, plots), e.g. after a newer semslam changed the report.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <memory>
#include <string>

#include "commands.h"
#include "semslam/report/html_report.h"

namespace semslam::cli {
namespace {

struct ReportArgs {
  std::string run_dir;
  std::string title;
  size_t max_points = HtmlReportOptions{}.max_points;
  bool quiet = false;  // read by main (-q quiets the log)
};

}  // namespace

void AddReportCommand(CLI::App& app) {
  auto args = std::make_shared<ReportArgs>();  // outlives parsing: the callback holds it
  auto* cmd = app.add_subcommand("report", "Rebuild report.html from a run folder");
  cmd->add_option("run_dir", args->run_dir, "Folder written by semslam run (with run.json)")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--title", args->title, "Page title (default: the sequence and the run folder)");
  cmd->add_option("--max-points", args->max_points, "Map points in the 3D view (a seeded random subset)")
      ->capture_default_str();
  cmd->add_flag("-q,--quiet", args->quiet, "Only errors on stderr");
  cmd->callback([args] {
    HtmlReportOptions options;
    options.title = args->title;
    options.max_points = args->max_points;
    const HtmlReportResult report = WriteHtmlReport(args->run_dir, options);
    spdlog::info("report: {} ({} of {} map points shown, {} bytes)", report.path.string(), report.points_shown,
                 report.map_points, report.bytes);
  });
}

}  // namespace semslam::cli
