#include "semslam/topology/topological_map.h"

#include <algorithm>
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/connected_components.hpp>
#include <cctype>
#include <cmath>
#include <map>
#include <numbers>

#include "semslam/core/error.h"

namespace semslam {

namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

std::string Lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The keyframe polyline parametrized by arc length.
class Path {
 public:
  explicit Path(const Points3d& points) : points_(points), arc_(points.size(), 0.0) {
    for (size_t i = 1; i < points_.size(); ++i) arc_[i] = arc_[i - 1] + (points_[i] - points_[i - 1]).norm();
  }
  double length() const { return arc_.empty() ? 0.0 : arc_.back(); }
  const std::vector<double>& arc() const { return arc_; }
  size_t size() const { return points_.size(); }

  Eigen::Vector3d At(double s) const {
    if (points_.size() == 1 || s <= 0) return points_.front();
    if (s >= length()) return points_.back();
    const size_t i =
        static_cast<size_t>(std::upper_bound(arc_.begin(), arc_.end(), s) - arc_.begin());  // >= 1
    const double span = arc_[i] - arc_[i - 1];
    const double t = span > 0 ? (s - arc_[i - 1]) / span : 0.0;
    return points_[i - 1] + t * (points_[i] - points_[i - 1]);
  }

  // Points of the path from arc a to arc b (a <= b), both ends interpolated.
  Points3d Between(double a, double b) const {
    Points3d out{At(a)};
    for (size_t i = 0; i < points_.size(); ++i) {
      if (arc_[i] > a && arc_[i] < b) out.push_back(points_[i]);
    }
    out.push_back(At(b));
    return out;
  }

 private:
  const Points3d& points_;
  std::vector<double> arc_;
};

double SignedAngleDeg(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)) * kRadToDeg;
}

struct Pass {
  double arc = 0.0;
  double distance = 0.0;
  int keyframe = 0;
};

// Passes of the path near `anchor` (horizontal): a pass begins within `radius` and ends beyond 1.5 radius, or
// where the path jumps to another drive (`segments`: each keyframe's; the stretch between two drives is not
// driven).
std::vector<Pass> FindPasses(const Points3d& points, const Path& path,
                             const std::vector<std::uint32_t>& segments, const Eigen::Vector3d& anchor,
                             double radius) {
  std::vector<Pass> passes;
  const Eigen::Vector2d a = anchor.head<2>();
  std::optional<Pass> current;
  const auto consider = [&](double arc, double d, int keyframe) {
    if (!current) {
      if (d < radius) current = Pass{arc, d, keyframe};
      return;
    }
    if (d < current->distance) *current = Pass{arc, d, keyframe};
    if (d > 1.5 * radius) {
      passes.push_back(*current);
      current.reset();
    }
  };
  if (points.size() == 1) {
    consider(0.0, (points[0].head<2>() - a).norm(), 0);
  }
  for (size_t k = 0; k + 1 < points.size(); ++k) {
    if (segments[k] != segments[k + 1]) {
      consider(path.arc()[k], (points[k].head<2>() - a).norm(), static_cast<int>(k));
      if (current) passes.push_back(*current);
      current.reset();
      continue;
    }
    const Eigen::Vector2d p = points[k].head<2>(), q = points[k + 1].head<2>();
    const Eigen::Vector2d d = q - p;
    const double len2 = d.squaredNorm();
    const double t = len2 > 0 ? std::clamp((a - p).dot(d) / len2, 0.0, 1.0) : 0.0;
    const double distance = (p + t * d - a).norm();
    const double arc = path.arc()[k] + t * (path.arc()[k + 1] - path.arc()[k]);
    const int keyframe = static_cast<int>(t < 0.5 ? k : k + 1);
    // The segment's start point first (it may be the far end of a pass), then its closest point.
    consider(path.arc()[k], (p - a).norm(), static_cast<int>(k));
    consider(arc, distance, keyframe);
  }
  if (!points.empty())
    consider(path.length(), (points.back().head<2>() - a).norm(), static_cast<int>(points.size() - 1));
  if (current) passes.push_back(*current);
  return passes;
}

}  // namespace

std::string_view TurnDirectionName(TurnDirection direction) {
  switch (direction) {
    case TurnDirection::kLeft:
      return "left";
    case TurnDirection::kRight:
      return "right";
    case TurnDirection::kUTurn:
      return "u-turn";
    case TurnDirection::kStraight:
      break;
  }
  return "straight";
}

TurnDirection ClassifyTurn(double signed_angle_deg, double straight_below_deg) {
  const double a = std::abs(signed_angle_deg);
  if (a < straight_below_deg) return TurnDirection::kStraight;
  if (a > 150.0) return TurnDirection::kUTurn;
  return signed_angle_deg > 0 ? TurnDirection::kLeft : TurnDirection::kRight;
}

void TopologyOptions::Check() const {
  Require(std::isfinite(turn_window_m) && turn_window_m > 0, "topology turn_window_m must be positive");
  Require(turn_threshold_deg > 0 && turn_threshold_deg < 180,
          "topology turn_threshold_deg must be in (0, 180)");
  Require(std::isfinite(fuse_distance_m) && fuse_distance_m > 0, "topology fuse_distance_m must be positive");
  Require(landmark_max_distance_m > 0, "topology landmark_max_distance_m must be positive");
  Require(straight_below_deg > 0 && straight_below_deg < 150,
          "topology straight_below_deg must be in (0, 150)");
  Require(std::isfinite(street_max_distance_m) && street_max_distance_m > 0,
          "topology street_max_distance_m must be positive");
}

std::optional<int> TopologicalMap::FindLandmark(std::string_view name) const {
  for (size_t i = 0; i < landmarks.size(); ++i) {
    if (landmarks[i].name == name) return static_cast<int>(i);
  }
  const std::string lower = Lower(name);
  std::optional<int> found;
  for (size_t i = 0; i < landmarks.size(); ++i) {
    if (Lower(landmarks[i].name) == lower) {
      if (found) return std::nullopt;  // ambiguous without case
      found = static_cast<int>(i);
    }
  }
  return found;
}

std::vector<std::string> TopologicalMap::LandmarkNames() const {
  std::vector<std::string> names;
  for (const TopoLandmark& l : landmarks) names.push_back(l.name);
  return names;
}

int TopologicalMap::NumLandmarkNodes() const {
  return static_cast<int>(
      std::count_if(nodes.begin(), nodes.end(), [](const TopoNode& n) { return n.is_landmark; }));
}

int TopologicalMap::NumTurnNodes() const {
  return static_cast<int>(
      std::count_if(nodes.begin(), nodes.end(), [](const TopoNode& n) { return n.is_turn; }));
}

int TopologicalMap::NumRevisitedNodes() const {
  return static_cast<int>(
      std::count_if(nodes.begin(), nodes.end(), [](const TopoNode& n) { return n.passes() > 1; }));
}

int TopologicalMap::CyclomaticNumber() const {
  if (nodes.empty()) return 0;
  boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS> graph(nodes.size());
  for (const TopoEdge& e : edges)
    boost::add_edge(static_cast<size_t>(e.from), static_cast<size_t>(e.to), graph);
  std::vector<int> component(nodes.size());
  const int components = boost::connected_components(graph, component.data());
  return static_cast<int>(edges.size()) - static_cast<int>(nodes.size()) + components;
}

TopologicalMap BuildTopologicalMap(const FramePositions& keyframes,
                                   const std::vector<PlacedLandmark>& landmarks,
                                   const Georeference& georeference, const TopologyOptions& options,
                                   const std::vector<Street>& streets) {
  options.Check();
  TopologicalMap map(georeference);
  map.options = options;

  Points3d points;
  points.reserve(keyframes.size());
  for (const FramePosition& k : keyframes) {
    Require(k.map_position.allFinite(), "topology: keyframe position is not finite");
    points.push_back(georeference.MapToEnu(k.map_position));
  }
  const Path path(points);
  // Each drive's stretch of the path (arc length): turn windows stay within it.
  std::vector<std::uint32_t> segments;
  for (const FramePosition& k : keyframes) segments.push_back(k.segment);
  std::vector<double> segment_start(keyframes.size()), segment_end(keyframes.size());
  for (size_t k = 0; k < keyframes.size(); ++k)
    segment_start[k] = k > 0 && segments[k] == segments[k - 1] ? segment_start[k - 1] : path.arc()[k];
  for (size_t k = keyframes.size(); k-- > 0;)
    segment_end[k] =
        k + 1 < keyframes.size() && segments[k] == segments[k + 1] ? segment_end[k + 1] : path.arc()[k];

  // 1. Heading change at each keyframe, and turn events at the peaks of runs above the threshold.
  map.keyframes.resize(keyframes.size());
  std::vector<double> change(keyframes.size(), 0.0);
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const double s = path.arc()[k];
    map.keyframes[k] = TopoKeyframe{keyframes[k], points[k], s, 0.0};
    if (s - options.turn_window_m < segment_start[k] || s + options.turn_window_m > segment_end[k]) continue;
    const Eigen::Vector2d before = (points[k] - path.At(s - options.turn_window_m)).head<2>();
    const Eigen::Vector2d after = (path.At(s + options.turn_window_m) - points[k]).head<2>();
    if (before.norm() < 1e-3 * options.turn_window_m || after.norm() < 1e-3 * options.turn_window_m) continue;
    change[k] = SignedAngleDeg(before, after);
    map.keyframes[k].heading_change_deg = change[k];
  }
  struct TurnEvent {
    int keyframe;
    double angle;
  };
  std::vector<TurnEvent> turns;
  for (size_t k = 0; k < change.size();) {
    if (std::abs(change[k]) <= options.turn_threshold_deg) {
      ++k;
      continue;
    }
    const double sign = change[k] > 0 ? 1.0 : -1.0;
    size_t peak = k;
    size_t end = k;
    while (end < change.size() && std::abs(change[end]) > options.turn_threshold_deg &&
           change[end] * sign > 0) {
      if (std::abs(change[end]) > std::abs(change[peak])) peak = end;
      ++end;
    }
    turns.push_back({static_cast<int>(peak), change[peak]});
    k = end;
  }

  // 2. Places: turn events first, then landmarks; one near an existing node's anchor joins it. A turn is
  // where streets meet, so a node that has one stays there: anchored at a landmark beside the corner, the
  // junction would move with it, and routes through the corner would go on to the landmark and turn around.
  const auto nearest_node = [&](const Eigen::Vector3d& p) -> int {
    int best = -1;
    double best_d = options.fuse_distance_m;
    for (const TopoNode& n : map.nodes) {
      const double d = (n.enu.head<2>() - p.head<2>()).norm();
      if (d <= best_d) {
        best_d = d;
        best = n.id;
      }
    }
    return best;
  };
  const auto new_node = [&](int keyframe) -> TopoNode& {
    TopoNode node;
    node.id = static_cast<int>(map.nodes.size());
    node.anchor_keyframe = keyframe;
    node.enu = points[static_cast<size_t>(keyframe)];
    map.nodes.push_back(node);
    return map.nodes.back();
  };

  // Per node: the sums of its left, right and u-turn angles.
  std::vector<Eigen::Vector3d> angle_sums;
  for (const TurnEvent& t : turns) {
    int node = nearest_node(points[static_cast<size_t>(t.keyframe)]);
    if (node < 0) node = new_node(t.keyframe).id;
    TopoNode& n = map.nodes[static_cast<size_t>(node)];
    n.is_turn = true;
    ++n.turn_events;
    angle_sums.resize(map.nodes.size(), Eigen::Vector3d::Zero());
    const TurnDirection direction = ClassifyTurn(t.angle, 0.0);
    const int kind = direction == TurnDirection::kUTurn ? 2 : direction == TurnDirection::kLeft ? 0 : 1;
    (kind == 0 ? n.left_turns : kind == 1 ? n.right_turns : n.u_turns)++;
    angle_sums[static_cast<size_t>(node)][kind] += t.angle;
  }
  for (const PlacedLandmark& placed : landmarks) {
    TopoLandmark l;
    l.name = placed.landmark.name;
    l.category = placed.landmark.category;
    l.wgs84 = placed.landmark.position;
    if (!placed.landmark.has_altitude)
      l.wgs84.altitude_m = georeference.enu_frame.ToWgs84(placed.enu).altitude_m;
    l.enu = placed.enu;
    l.map_position = placed.map_position;
    int nearest = -1;
    double nearest_d = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < points.size(); ++k) {
      const double d = (points[k].head<2>() - placed.enu.head<2>()).norm();
      if (d < nearest_d) {
        nearest_d = d;
        nearest = static_cast<int>(k);
      }
    }
    l.distance_m = nearest >= 0 ? nearest_d : 0.0;
    const int index = static_cast<int>(map.landmarks.size());
    if (nearest >= 0 && nearest_d <= options.landmark_max_distance_m) {
      int node = nearest_node(points[static_cast<size_t>(nearest)]);
      if (node < 0) node = new_node(nearest).id;
      map.nodes[static_cast<size_t>(node)].is_landmark = true;
      map.nodes[static_cast<size_t>(node)].landmarks.push_back(index);
      l.node = node;
    }
    map.landmarks.push_back(std::move(l));
  }
  for (TopoNode& n : map.nodes) {
    const size_t i = static_cast<size_t>(n.id);
    if (n.is_turn) {
      const int most = std::max({n.left_turns, n.right_turns, n.u_turns});
      const int kind = n.left_turns == most ? 0 : n.right_turns == most ? 1 : 2;
      n.turn = kind == 0 ? TurnDirection::kLeft : kind == 1 ? TurnDirection::kRight : TurnDirection::kUTurn;
      n.turn_angle_deg = angle_sums[i][kind] / most;
    }
    n.map_position = georeference.EnuToMap(n.enu);
    n.wgs84 = georeference.enu_frame.ToWgs84(n.enu);
  }

  // 3. Visits and edges.
  struct Visit {
    double arc;
    int node;
    int keyframe;
  };
  std::vector<Visit> visits;
  for (TopoNode& n : map.nodes) {
    for (const Pass& pass : FindPasses(points, path, segments, n.enu, options.fuse_distance_m)) {
      n.visit_arc_m.push_back(pass.arc);
      n.visit_keyframes.push_back(pass.keyframe);
      visits.push_back({pass.arc, n.id, pass.keyframe});
    }
  }
  std::sort(visits.begin(), visits.end(),
            [](const Visit& a, const Visit& b) { return a.arc != b.arc ? a.arc < b.arc : a.node < b.node; });
  std::map<std::pair<int, int>, int> edge_of_pair;
  for (size_t i = 1; i < visits.size(); ++i) {
    const Visit& a = visits[i - 1];
    const Visit& b = visits[i];
    if (a.node == b.node) continue;
    // Consecutive visits of different drives: nothing was driven between them.
    if (segments[static_cast<size_t>(a.keyframe)] != segments[static_cast<size_t>(b.keyframe)]) continue;
    const double length = b.arc - a.arc;
    const std::pair<int, int> key{std::min(a.node, b.node), std::max(a.node, b.node)};
    const auto it = edge_of_pair.find(key);
    if (it == edge_of_pair.end()) {
      TopoEdge e;
      e.id = static_cast<int>(map.edges.size());
      e.from = a.node;
      e.to = b.node;
      e.length_m = length;
      e.polyline_enu = path.Between(a.arc, b.arc);
      edge_of_pair[key] = e.id;
      map.edges.push_back(std::move(e));
      continue;
    }
    TopoEdge& e = map.edges[static_cast<size_t>(it->second)];
    ++e.traversals;
    if (length < e.length_m) {
      e.length_m = length;
      e.polyline_enu = path.Between(a.arc, b.arc);
      if (e.from != a.node) std::reverse(e.polyline_enu.begin(), e.polyline_enu.end());
    }
  }

  // 4. Streets.
  if (!streets.empty()) LabelEdgeStreets(map, StreetsToEnu(streets, georeference.enu_frame));
  return map;
}

}  // namespace semslam
