#pragma once
// Shortest routes between landmarks on the topological map (Dijkstra, Boost.Graph), as steps a person can
// follow: "Drive 120 m to Town Hall (on your left).", "Turn left.", ...

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/topology/topological_map.h"

namespace semslam {

struct RouteStep {
  enum class Kind { kStart, kDrive, kTurn, kArrive };
  Kind kind = Kind::kDrive;
  double distance_m = 0.0;                        // kDrive
  TurnDirection turn = TurnDirection::kStraight;  // kTurn
  int node = -1;                                  // where the step ends
  std::string text;
};

struct Route {
  int from_landmark = -1, to_landmark = -1;
  std::vector<int> nodes;  // node ids, start to end
  std::vector<int> edges;  // edge ids, one fewer than nodes
  double length_m = 0.0;
  Points3d polyline_enu;  // the whole route, oriented
  std::vector<RouteStep> steps;
};

// Throws InvalidArgument for an unknown name (the message lists the known ones) or a landmark without a node,
// and std::runtime_error when the two are not connected.
Route FindRoute(const TopologicalMap& map, std::string_view from_name, std::string_view to_name);
// Dijkstra between two node ids (nodes empty when unreachable).
Route ShortestPath(const TopologicalMap& map, int from_node, int to_node);
// Turn-by-turn steps of a route (filled in by FindRoute).
std::vector<RouteStep> DescribeRoute(const TopologicalMap& map, const Route& route);
// Human-friendly rounding of a distance: "85 m", "120 m", "1.2 km".
std::string FormatDistance(double metres);

// A FeatureCollection: the route as a LineString (WGS84) with its steps and length in the properties, and the
// nodes it passes as Points.
void WriteRouteGeoJson(const std::filesystem::path& path, const TopologicalMap& map, const Route& route);

}  // namespace semslam
