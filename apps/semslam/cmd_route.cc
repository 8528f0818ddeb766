// semslam route --map FILE --from NAME --to NAME [--out FILE] [--json]: the shortest route between two
// landmarks of a saved topological map, as steps a person can follow. FILE is a topology.json or a
// map.semslam whose extra section "topology" holds the same JSON.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.h"
#include "semslam/core/error.h"
#include "semslam/map/map_file.h"
#include "semslam/topology/routing.h"
#include "semslam/topology/topological_map.h"

namespace semslam::cli {
namespace {

namespace fs = std::filesystem;

struct RouteArgs {
  std::string map;
  std::string from;
  std::string to;
  std::string out;
  bool json = false;
};

bool IsMapFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  char magic[8] = {};
  in.read(magic, sizeof(magic));
  return in.gcount() == 8 && std::string(magic, 8) == "SEMSLMAP";
}

TopologicalMap LoadTopology(const fs::path& path) {
  if (!fs::is_regular_file(path)) throw InputError(path, "no such file");
  if (!IsMapFile(path)) return ReadTopologyJson(path);
  Map map;
  const MapFileContents contents = ReadMapFile(path, map);
  const auto it = contents.extra_sections.find("topology");
  if (it == contents.extra_sections.end()) {
    throw InputError(path, "the map has no topological map (it was built without GPS or landmarks)");
  }
  return ParseTopologyJson(it->second, fs::path(path.string() + "#topology"));
}

void Run(const RouteArgs& args) {
  const TopologicalMap map = LoadTopology(args.map);
  const Route route = FindRoute(map, args.from, args.to);
  if (!args.out.empty()) WriteRouteGeoJson(args.out, map, route);
  if (args.json) {
    nlohmann::json steps = nlohmann::json::array();
    for (const RouteStep& step : route.steps) steps.push_back(step.text);
    const nlohmann::json j = {{"from", map.landmarks[static_cast<size_t>(route.from_landmark)].name},
                              {"to", map.landmarks[static_cast<size_t>(route.to_landmark)].name},
                              {"length_m", route.length_m},
                              {"nodes", route.nodes},
                              {"steps", steps}};
    std::printf("%s\n", j.dump(1).c_str());
    return;
  }
  std::printf("Route from %s to %s, %s:\n",
              map.landmarks[static_cast<size_t>(route.from_landmark)].name.c_str(),
              map.landmarks[static_cast<size_t>(route.to_landmark)].name.c_str(),
              FormatDistance(route.length_m).c_str());
  for (size_t i = 0; i < route.steps.size(); ++i)
    std::printf("%3zu. %s\n", i + 1, route.steps[i].text.c_str());
}

}  // namespace

void AddRouteCommand(CLI::App& app) {
  auto args = std::make_shared<RouteArgs>();
  auto* cmd = app.add_subcommand("route", "Print the shortest route between two landmarks of a saved map");
  cmd->add_option("--map", args->map, "topology.json, or a map.semslam with a topology section")->required();
  cmd->add_option("--from", args->from, "Start landmark (name; case-insensitive when unambiguous)")
      ->required();
  cmd->add_option("--to", args->to, "Destination landmark")->required();
  cmd->add_option("--out", args->out, "Also write the route as GeoJSON (WGS84) to this file");
  cmd->add_flag("--json", args->json, "Print the route as JSON instead of text");
  cmd->callback([args] { Run(*args); });
}

}  // namespace semslam::cli
