// semslam: visual semantic SLAM with landmarks. See README.md and `semslam <command> --help`.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "cli_support.h"
#include "commands.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"

int main(int argc, char** argv) {
#ifdef SEMSLAM_THREAD_SANITIZER_BUILD
  // libtbb is not built with TSan, so TSan cannot see how its workers hand their results back and reports every
  // parallel loop: under TSan, TBB runs on the calling thread only, and TSan checks the pipeline's own threads
  // (tracking, mapping, loop closing, segmentation).
  const tbb::global_control one_tbb_thread(tbb::global_control::max_allowed_parallelism, 1);
#endif
  namespace cli = semslam::cli;
  cli::SetCommandLine(argc, argv);
  // Logs go to stderr (stdout carries results: eval's JSON, routes), and to run.log in a run folder.
  auto console = std::make_shared<spdlog::sinks::stderr_color_sink_mt>();
  auto logger = std::make_shared<spdlog::logger>("semslam", console);
  logger->set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  spdlog::set_default_logger(logger);

  CLI::App app{"semslam: visual semantic SLAM with landmarks for large-scale outdoor driving"};
  app.require_subcommand(1);
  app.set_version_flag("--version", cli::VersionLine());
  bool verbose = false, quiet = false;
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  app.add_flag("-q,--quiet", quiet, "Only errors on stderr (no log messages, no progress lines)");

  cli::AddDemoCommand(app);
  cli::AddSynthCommand(app);
  cli::AddRunCommand(app);
  cli::AddMergeCommand(app);
  cli::AddLocalizeCommand(app);
  cli::AddRouteCommand(app);
  cli::AddEvalCommand(app);
  cli::AddReportCommand(app);
  cli::AddVocabCommand(app);
  cli::AddSegmentCommand(app);
  cli::AddBenchCommand(app);
  cli::AddComposeCommand(app);

  app.parse_complete_callback([&] {
    // -q also counts after the subcommand (every subcommand has one).
    for (const CLI::App* sub : app.get_subcommands()) {
      if (const CLI::Option* q = sub->get_option_no_throw("--quiet"); q != nullptr && q->count() > 0) quiet = true;
    }
    cli::SetQuiet(quiet);
    logger->set_level(verbose ? spdlog::level::debug : spdlog::level::info);
    console->set_level(quiet ? spdlog::level::err : spdlog::level::trace);
  });

  // Ctrl-C / SIGTERM: long commands finish the current frame and save what they did; a second one quits.
  semslam::InstallInterruptHandlers();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version print and succeed; a bad command line gets one line, like every other error.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    // A typo explains the error best ("--sequence is required" is only its consequence).
    const std::string hint = cli::SuggestCorrections(app, app.remaining(true));
    std::fprintf(stderr, "semslam: bad command line: %s (see --help)\n", hint.empty() ? e.what() : hint.c_str());
    return 2;
  } catch (const semslam::Interrupted& e) {
    std::fprintf(stderr, "semslam: %s\n", e.what());
    return e.ExitCode();
  } catch (const semslam::InputError& e) {
    spdlog::default_logger()->flush();
    std::fprintf(stderr, "semslam: input error: %s\n", e.what());
    return 1;
  } catch (const semslam::InvalidArgument& e) {
    std::fprintf(stderr, "semslam: invalid argument: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "semslam: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
