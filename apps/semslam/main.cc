// semslam: visual semantic SLAM with landmarks. See README.md and `semslam <command> --help`.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "commands.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"

int main(int argc, char** argv) {
  CLI::App app{"semslam: visual semantic SLAM with landmarks for large-scale outdoor driving"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "semslam 0.1.0");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Log debug messages");
  app.parse_complete_callback(
      [&] { spdlog::set_level(verbose ? spdlog::level::debug : spdlog::level::info); });
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");

  semslam::cli::AddDemoCommand(app);
  semslam::cli::AddSynthCommand(app);
  semslam::cli::AddRunCommand(app);
  semslam::cli::AddLocalizeCommand(app);
  semslam::cli::AddRouteCommand(app);
  semslam::cli::AddEvalCommand(app);
  semslam::cli::AddVocabCommand(app);
  semslam::cli::AddSegmentCommand(app);
  semslam::cli::AddBenchCommand(app);

  // Ctrl-C / SIGTERM: long commands finish the current frame and save what they did; a second one quits.
  semslam::InstallInterruptHandlers();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version print and succeed; a bad command line gets one line, like every other error.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::fprintf(stderr, "semslam: bad command line: %s (see --help)\n", e.what());
    return 2;
  } catch (const semslam::Interrupted& e) {
    std::fprintf(stderr, "semslam: %s\n", e.what());
    return e.ExitCode();
  } catch (const semslam::InputError& e) {
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
