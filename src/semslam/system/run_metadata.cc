#include "semslam/system/run_metadata.h"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <ctime>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "semslam/core/error.h"
#include "semslam/place/vocabulary.h"
#include "semslam/system/sequence_runner.h"
#include "semslam/system/slam_config.h"

namespace semslam {

namespace {

std::string UtcNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return text;
}

std::string Absolute(const std::filesystem::path& path) {
  if (path.empty()) return "";
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  return (error ? path : absolute).lexically_normal().string();
}

// A YAML scalar as the JSON value it reads as: integer, number, boolean or string.
nlohmann::json ScalarJson(const YAML::Node& node) {
  const std::string text = node.Scalar();
  try {
    size_t used = 0;
    const long long integer = std::stoll(text, &used);
    if (used == text.size()) return integer;
  } catch (const std::exception&) {
  }
  try {
    size_t used = 0;
    const double number = std::stod(text, &used);
    if (used == text.size()) return number;
  } catch (const std::exception&) {
  }
  if (text == "true") return true;
  if (text == "false") return false;
  return text;
}

nlohmann::json YamlToJson(const YAML::Node& node) {
  if (node.IsMap()) {
    nlohmann::json object = nlohmann::json::object();
    for (const auto& entry : node) object[entry.first.as<std::string>()] = YamlToJson(entry.second);
    return object;
  }
  if (node.IsSequence()) {
    nlohmann::json array = nlohmann::json::array();
    for (const auto& item : node) array.push_back(YamlToJson(item));
    return array;
  }
  if (node.IsScalar()) return ScalarJson(node);
  return nullptr;
}

bool NeedsQuotes(const std::string& argument) {
  if (argument.empty()) return true;
  for (const char c : argument) {
    const bool plain = std::isalnum(static_cast<unsigned char>(c)) != 0 ||
                       std::string_view("-_./:=,+@%").find(c) != std::string_view::npos;
    if (!plain) return true;
  }
  return false;
}

}  // namespace

std::string VersionLine(const RunProvenance& provenance) {
  return "semslam " + provenance.version + " (commit " + provenance.commit + ", " + provenance.build_type +
         ")";
}

std::vector<std::string> ProvenanceLines(const RunProvenance& provenance) {
  return {VersionLine(provenance), "command: " + ShellQuote(provenance.command)};
}

std::string ShellQuote(const std::vector<std::string>& arguments) {
  std::string line;
  for (const std::string& argument : arguments) {
    if (!line.empty()) line += ' ';
    if (!NeedsQuotes(argument)) {
      line += argument;
      continue;
    }
    line += '\'';
    for (const char c : argument) line += c == '\'' ? std::string("'\\''") : std::string(1, c);
    line += '\'';
  }
  return line;
}

nlohmann::json ReadJsonFile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot be read");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path, fmt::format("not valid JSON: {}", e.what()));
  }
}

nlohmann::json ProvenanceJson(const RunProvenance& provenance) {
  std::error_code error;
  const std::filesystem::path cwd = std::filesystem::current_path(error);
  return {{"command", provenance.command},
          {"command_line", ShellQuote(provenance.command)},
          {"version", provenance.version.empty() ? "unknown" : provenance.version},
          {"commit", provenance.commit.empty() ? "unknown" : provenance.commit},
          {"build_type", provenance.build_type},
          {"date", UtcNow()},
          {"host_cores", std::thread::hardware_concurrency()},
          {"working_directory", error ? "" : cwd.string()}};
}

nlohmann::json EffectiveConfigJson(const RunOptions& options, const SlamOptions& slam, size_t end_frame) {
  const std::filesystem::path vocabulary =
      slam.vocabulary.empty() ? DefaultVocabularyPath() : slam.vocabulary;
  return {
      {"sequence", Absolute(options.sequence)},
      {"output", Absolute(options.output)},
      {"frames", {options.first_frame, end_frame}},
      {"mode", slam.mode == SensorMode::kStereo ? "stereo" : "mono"},
      {"pacing", std::string(PacingName(slam.pacing))},
      {"segmenter", options.segmenter},
      {"seed", options.seed},
      {"gps", Absolute(options.gps)},
      {"gps_every", options.gps_every},
      {"gps_fusion", options.gps_fusion},
      {"gps_lever_arm", options.gps_antenna_in_camera_m ? nlohmann::json{options.gps_antenna_in_camera_m->x(),
                                                                         options.gps_antenna_in_camera_m->y(),
                                                                         options.gps_antenna_in_camera_m->z()}
                                                        : nlohmann::json(nullptr)},
      {"landmarks", Absolute(options.landmarks)},
      {"camera_height_m", options.camera_height_m},
      {"map_in", Absolute(options.map_in)},
      {"localization_only", slam.localization_only},
      {"exclude_dynamic", slam.exclude_dynamic},
      {"vocabulary", Absolute(vocabulary)},
      {"slam", YamlToJson(YAML::Load(SlamConfigToYaml(slam)))}};
}

}  // namespace semslam
