#include "cli_support.h"

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <numeric>

#include "semslam_build_info.h"

namespace semslam::cli {

namespace {
bool quiet = false;
RunProvenance provenance;

// Renamed options, so that an old command line gets the new name.
struct Renamed {
  const char* command;
  const char* old_name;
  const char* new_name;
};
constexpr Renamed kRenamed[] = {{"localize", "--landmarks", "--nearest-landmarks"}};

// The deepest subcommand the command line selected ("" and the app itself when none).
const CLI::App* SelectedCommand(const CLI::App& app) {
  const CLI::App* current = &app;
  for (;;) {
    const auto chosen = current->get_subcommands();
    if (chosen.empty()) return current;
    current = chosen.front();
  }
}

std::string Closest(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  size_t best_distance = std::numeric_limits<size_t>::max();
  for (const std::string& candidate : candidates) {
    const size_t d = EditDistance(word, candidate);
    if (d < best_distance) {
      best_distance = d;
      best = candidate;
    }
  }
  // Close: a typo or two, or the word is the start of the candidate (--frame for --frames).
  const size_t allowed = std::max<size_t>(2, word.size() / 3);
  const bool prefix = word.size() >= 4 && best.rfind(word, 0) == 0;
  return best_distance <= allowed || prefix ? best : "";
}
}  // namespace

bool Quiet() { return quiet; }
void SetQuiet(bool value) { quiet = value; }

std::string VersionLine() {
  RunProvenance binary;
  binary.version = std::string(build_info::kVersion);
  binary.commit = std::string(build_info::kCommit);
  binary.build_type = std::string(build_info::kBuildType);
  return semslam::VersionLine(binary);
}

const RunProvenance& Provenance() { return provenance; }

void SetCommandLine(int argc, char** argv) {
  provenance.command.assign(argv, argv + argc);
  provenance.version = std::string(build_info::kVersion);
  provenance.commit = std::string(build_info::kCommit);
  provenance.build_type = std::string(build_info::kBuildType);
}

std::vector<std::string> LogHeader() { return ProvenanceLines(provenance); }

size_t EditDistance(const std::string& a, const std::string& b) {
  const size_t n = a.size(), m = b.size();
  std::vector<std::vector<size_t>> d(n + 1, std::vector<size_t>(m + 1));
  for (size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (size_t i = 1; i <= n; ++i) {
    for (size_t j = 1; j <= m; ++j) {
      const size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

std::string SuggestCorrections(const CLI::App& app, const std::vector<std::string>& unexpected) {
  const CLI::App* command = SelectedCommand(app);
  std::vector<std::string> options, subcommands;
  std::vector<const CLI::App*> scopes = {command};
  if (command != &app) scopes.push_back(&app);  // -v, -q and --version go before the subcommand
  for (const CLI::App* scope : scopes) {
    for (const CLI::Option* option : scope->get_options()) {
      for (const std::string& name : option->get_lnames()) options.push_back("--" + name);
    }
  }
  for (const CLI::App* sub : command->get_subcommands([](const CLI::App*) { return true; })) {
    subcommands.push_back(sub->get_name());
  }
  std::string text;
  for (const std::string& word : unexpected) {
    std::string suggestion;
    if (word.rfind("--", 0) == 0) {
      const std::string name = word.substr(0, word.find('='));
      for (const Renamed& r : kRenamed) {
        if (command->get_name() == r.command && name == r.old_name) suggestion = r.new_name;
      }
      if (suggestion.empty()) suggestion = Closest(name, options);
      if (suggestion == name) suggestion.clear();
    } else if (!word.empty() && word.front() != '-' && !subcommands.empty()) {
      suggestion = Closest(word, subcommands);
    }
    if (!suggestion.empty()) {
      text += (text.empty() ? "" : "; ") + std::string(word.rfind("-", 0) == 0 ? "unknown option " : "unknown command ") +
              word + ": did you mean " + suggestion + "?";
    }
  }
  return text;
}

void AddCameraAndOutputOptions(CLI::App& cmd, CameraAndOutputArgs& args) {
  cmd.add_option(
      "--camera", args.camera,
      "Camera of a KITTI folder: image_00..image_03 of a raw drive, image_0..image_3 of an odometry sequence "
      "(default image_00 / image_0); stereo uses the pair 00/01 or 02/03 (0/1 or 2/3)");
  cmd.add_option("--out", args.out,
                 "Output folder (created if missing). A folder holding an earlier run is refused unless "
                 "--overwrite is given; two commands never write into one folder at once")
      ->required();
  cmd.add_flag("--overwrite", args.overwrite,
               "Replace the earlier run in --out: everything in that folder is removed before the first frame");
  cmd.add_option("--max-bad-frames", args.max_bad_frames,
                 "Unreadable or damaged frames are skipped with a warning; more than this many in a row stop "
                 "the command, which still saves what it did")
      ->capture_default_str();
}

}  // namespace semslam::cli
