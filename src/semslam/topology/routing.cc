#include "semslam/topology/routing.h"

#include <fmt/format.h>

#include <algorithm>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/dijkstra_shortest_paths.hpp>
#include <cmath>
#include <map>
#include <numbers>
#include <stdexcept>

#include "semslam/core/error.h"

namespace semslam {

namespace {

struct EdgeProperties {
  double length = 0.0;
  int id = -1;
};
using Graph =
    boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property, EdgeProperties>;

double PolylineLength(const Points3d& points) {
  double length = 0.0;
  for (size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

Eigen::Vector3d PointAt(const Points3d& points, const std::vector<double>& arc, double s) {
  if (s <= 0 || points.size() == 1) return points.front();
  if (s >= arc.back()) return points.back();
  const size_t i = static_cast<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin());
  const double span = arc[i] - arc[i - 1];
  const double t = span > 0 ? (s - arc[i - 1]) / span : 0.0;
  return points[i - 1] + t * (points[i] - points[i - 1]);
}

std::string Compass(const Eigen::Vector2d& direction) {
  static const char* kNames[] = {"north", "north-east", "east", "south-east",
                                 "south", "south-west", "west", "north-west"};
  const double bearing =
      std::atan2(direction.x(), direction.y()) * 180.0 / std::numbers::pi;  // from north, clockwise
  const int sector = static_cast<int>(std::lround((bearing < 0 ? bearing + 360.0 : bearing) / 45.0)) % 8;
  return kNames[sector];
}

// "on your left/right" for a landmark seen from `at` while travelling along `direction`; empty when it is
// (nearly) ahead or behind or too close to tell.
std::string Side(const Eigen::Vector3d& at, const Eigen::Vector2d& direction,
                 const Eigen::Vector3d& landmark) {
  const Eigen::Vector2d to = (landmark - at).head<2>();
  if (to.norm() < 2.0 || direction.norm() < 1e-9) return {};
  const double cross = direction.x() * to.y() - direction.y() * to.x();
  const double sine = cross / (direction.norm() * to.norm());
  if (std::abs(sine) < 0.2) return {};
  return sine > 0 ? " (on your left)" : " (on your right)";
}

std::string NodeNames(const TopologicalMap& map, int node) {
  std::string names;
  for (const int l : map.nodes[static_cast<size_t>(node)].landmarks) {
    if (!names.empty()) names += " / ";
    names += map.landmarks[static_cast<size_t>(l)].name;
  }
  return names;
}

std::string Capitalized(std::string s) {
  if (!s.empty() && s[0] >= 'a' && s[0] <= 'z') s[0] = static_cast<char>(s[0] - 'a' + 'A');
  return s;
}

}  // namespace

std::string FormatDistance(double metres) {
  if (!(metres >= 0) || !std::isfinite(metres)) return "? m";
  if (metres >= 1000.0) return fmt::format("{:.1f} km", metres / 1000.0);
  double step = 1.0;
  if (metres >= 100.0) {
    step = 10.0;
  } else if (metres >= 20.0) {
    step = 5.0;
  }
  return fmt::format("{:.0f} m", std::round(metres / step) * step);
}

Route ShortestPath(const TopologicalMap& map, int from_node, int to_node) {
  const size_t n = map.nodes.size();
  Require(from_node >= 0 && static_cast<size_t>(from_node) < n && to_node >= 0 &&
              static_cast<size_t>(to_node) < n,
          "route: node id out of range");
  Graph graph(n);
  for (const TopoEdge& e : map.edges) {
    boost::add_edge(static_cast<size_t>(e.from), static_cast<size_t>(e.to), EdgeProperties{e.length_m, e.id},
                    graph);
  }
  std::vector<size_t> predecessor(n);
  std::vector<double> distance(n);
  boost::dijkstra_shortest_paths(graph, static_cast<size_t>(from_node),
                                 boost::predecessor_map(predecessor.data())
                                     .distance_map(distance.data())
                                     .weight_map(boost::get(&EdgeProperties::length, graph)));

  Route route;
  if (from_node != to_node && predecessor[static_cast<size_t>(to_node)] == static_cast<size_t>(to_node))
    return route;
  for (size_t v = static_cast<size_t>(to_node);; v = predecessor[v]) {
    route.nodes.push_back(static_cast<int>(v));
    if (v == static_cast<size_t>(from_node)) break;
  }
  std::reverse(route.nodes.begin(), route.nodes.end());
  route.length_m = distance[static_cast<size_t>(to_node)];

  route.polyline_enu.push_back(map.nodes[static_cast<size_t>(from_node)].enu);
  for (size_t i = 1; i < route.nodes.size(); ++i) {
    const size_t a = static_cast<size_t>(route.nodes[i - 1]), b = static_cast<size_t>(route.nodes[i]);
    // The shortest edge between a and b (the map keeps one per pair; be safe with several).
    int best = -1;
    for (const auto e : boost::make_iterator_range(boost::out_edges(a, graph))) {
      if (boost::target(e, graph) != b) continue;
      if (best < 0 || graph[e].length < map.edges[static_cast<size_t>(best)].length_m) best = graph[e].id;
    }
    route.edges.push_back(best);
    const TopoEdge& edge = map.edges[static_cast<size_t>(best)];
    Points3d piece = edge.polyline_enu;
    if (edge.from != static_cast<int>(a)) std::reverse(piece.begin(), piece.end());
    route.polyline_enu.insert(route.polyline_enu.end(), piece.begin() + (piece.empty() ? 0 : 1), piece.end());
  }
  return route;
}

std::vector<RouteStep> DescribeRoute(const TopologicalMap& map, const Route& route) {
  std::vector<RouteStep> steps;
  if (route.nodes.empty()) return steps;
  const Points3d& line = route.polyline_enu;
  std::vector<double> arc(line.size(), 0.0);
  for (size_t i = 1; i < line.size(); ++i) arc[i] = arc[i - 1] + (line[i] - line[i - 1]).norm();
  // Arc position of each route node.
  std::vector<double> node_arc{0.0};
  for (const int e : route.edges) {
    node_arc.push_back(node_arc.back() + PolylineLength(map.edges[static_cast<size_t>(e)].polyline_enu));
  }
  const double window = map.options.turn_window_m;
  const auto direction_before = [&](size_t i) -> Eigen::Vector2d {
    const double s0 = std::max(node_arc[i] - window, i > 0 ? node_arc[i - 1] : 0.0);
    return (PointAt(line, arc, node_arc[i]) - PointAt(line, arc, s0)).head<2>();
  };
  const auto direction_after = [&](size_t i) -> Eigen::Vector2d {
    const double s1 = std::min(node_arc[i] + window, i + 1 < node_arc.size() ? node_arc[i + 1] : arc.back());
    return (PointAt(line, arc, s1) - PointAt(line, arc, node_arc[i])).head<2>();
  };
  const auto landmark_side = [&](int node, const Eigen::Vector2d& direction,
                                 int landmark = -1) -> std::string {
    const TopoNode& n = map.nodes[static_cast<size_t>(node)];
    if (landmark < 0 && n.landmarks.empty()) return {};
    if (landmark < 0) landmark = n.landmarks.front();
    const TopoLandmark& l = map.landmarks[static_cast<size_t>(landmark)];
    if (l.category == kCornerCategory) return {};  // a corner is where the road goes, not beside it
    return Side(n.enu, direction, l.enu);
  };
  // The street of the route's i-th edge (from node i to node i + 1); empty when not known.
  const auto street = [&](size_t i) -> const std::string& {
    return map.edges[static_cast<size_t>(route.edges[i])].street;
  };
  // " along S" for the drive over edges [first, last): S covers more than half of its length.
  const auto along = [&](size_t first, size_t last) -> std::string {
    std::map<std::string, double> length;
    for (size_t i = first; i < last; ++i) {
      if (!street(i).empty()) length[street(i)] += node_arc[i + 1] - node_arc[i];
    }
    for (const auto& [name, l] : length) {
      if (2.0 * l > node_arc[last] - node_arc[first]) return " along " + name;
    }
    return {};
  };

  const int first = route.nodes.front(), last = route.nodes.back();
  const auto endpoint_name = [&](int landmark, int node) {
    return landmark >= 0 ? map.landmarks[static_cast<size_t>(landmark)].name : NodeNames(map, node);
  };
  RouteStep start;
  start.kind = RouteStep::Kind::kStart;
  start.node = first;
  start.text = fmt::format("Start at {}", endpoint_name(route.from_landmark, first));
  if (route.nodes.size() > 1) start.text += fmt::format(", heading {}", Compass(direction_after(0)));
  start.text += ".";
  steps.push_back(start);

  double pending = 0.0;
  size_t drive_start = 0;  // the node the current drive began at
  for (size_t i = 1; i < route.nodes.size(); ++i) {
    pending += node_arc[i] - node_arc[i - 1];
    const int node = route.nodes[i];
    const std::string names =
        i + 1 == route.nodes.size() ? endpoint_name(route.to_landmark, node) : NodeNames(map, node);
    if (i + 1 == route.nodes.size()) {
      steps.push_back({RouteStep::Kind::kDrive, pending, TurnDirection::kStraight, node,
                       fmt::format("Drive {}{} to {}{}.", FormatDistance(pending), along(drive_start, i),
                                   names, landmark_side(node, direction_before(i), route.to_landmark))});
      break;
    }
    const Eigen::Vector2d before = direction_before(i), after = direction_after(i);
    const double angle =
        before.norm() > 1e-9 && after.norm() > 1e-9
            ? std::atan2(before.x() * after.y() - before.y() * after.x(), before.dot(after)) * 180.0 /
                  std::numbers::pi
            : 0.0;
    const TurnDirection turn = ClassifyTurn(angle, map.options.straight_below_deg);
    // Where the street ahead is known and another than the one behind, the step names it.
    const std::string& next_street = street(i);
    const bool new_street = !next_street.empty() && next_street != street(i - 1);
    // Keep driving straight on, unless at a named place or into a street of another name.
    if (turn == TurnDirection::kStraight && names.empty() && !(new_street && !street(i - 1).empty()))
      continue;
    const std::string way = along(drive_start, i);
    steps.push_back({RouteStep::Kind::kDrive, pending, TurnDirection::kStraight, node,
                     names.empty() ? fmt::format("Drive {}{}.", FormatDistance(pending), way)
                                   : fmt::format("Drive {}{} to {}{}.", FormatDistance(pending), way, names,
                                                 landmark_side(node, before))});
    pending = 0.0;
    drive_start = i;
    const std::string into = new_street ? " into " + next_street : std::string();
    if (turn == TurnDirection::kUTurn) {
      steps.push_back({RouteStep::Kind::kTurn, 0.0, turn, node, "Turn around."});
    } else if (turn != TurnDirection::kStraight) {
      steps.push_back({RouteStep::Kind::kTurn, 0.0, turn, node,
                       fmt::format("Turn {}{}.", TurnDirectionName(turn), into)});
    } else if (new_street) {
      steps.push_back({RouteStep::Kind::kTurn, 0.0, turn, node, fmt::format("Continue straight{}.", into)});
    }
  }
  RouteStep arrive;
  arrive.kind = RouteStep::Kind::kArrive;
  arrive.node = last;
  arrive.text = fmt::format("You have arrived at {} ({} in all).", endpoint_name(route.to_landmark, last),
                            FormatDistance(route.length_m));
  steps.push_back(arrive);
  for (RouteStep& step : steps) step.text = Capitalized(step.text);
  return steps;
}

Route FindRoute(const TopologicalMap& map, std::string_view from_name, std::string_view to_name) {
  const auto resolve = [&](std::string_view name) -> int {
    const auto index = map.FindLandmark(name);
    if (!index) {
      std::string known;
      for (const std::string& n : map.LandmarkNames()) known += (known.empty() ? "" : ", ") + ("'" + n + "'");
      throw InvalidArgument(fmt::format("unknown landmark '{}'; the map knows {}", name,
                                        known.empty() ? std::string("no landmarks") : known));
    }
    if (map.landmarks[static_cast<size_t>(*index)].node < 0) {
      throw InvalidArgument(
          fmt::format("landmark '{}' is {} from the driven trajectory: it has no node to route to", name,
                      FormatDistance(map.landmarks[static_cast<size_t>(*index)].distance_m)));
    }
    return *index;
  };
  const int from = resolve(from_name), to = resolve(to_name);
  Route route = ShortestPath(map, map.landmarks[static_cast<size_t>(from)].node,
                             map.landmarks[static_cast<size_t>(to)].node);
  if (route.nodes.empty()) {
    throw std::runtime_error(fmt::format(
        "no route from '{}' to '{}': they are not connected in the topological map", from_name, to_name));
  }
  route.from_landmark = from;
  route.to_landmark = to;
  route.steps = DescribeRoute(map, route);
  return route;
}

}  // namespace semslam
