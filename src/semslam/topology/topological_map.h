#pragma once
// The topological semantic map (paper §III-D.2): nodes are the places where the driven trajectory meets a
// landmark (its nearest keyframe) or turns; edges are reachability along the driven trajectory, with length;
// a place passed again later is the same node, which closes the graph's cycles.
//
// Construction, in a metric level frame (ENU through the georeference):
//  1. Turn events: at each keyframe, the signed heading change between the path's direction over the
//     `turn_window_m` before it and over the `turn_window_m` after it (positive = counter-clockwise = left).
//     Each run of keyframes above `turn_threshold_deg` with one sign gives one event, at its peak.
//  2. Places: turn events first, then landmarks within `landmark_max_distance_m` of the trajectory (at their
//     nearest keyframe); one within `fuse_distance_m` of an existing node's anchor joins that node (same
//     place: a revisit, two landmarks at one spot, a landmark at a corner, which joins the corner's node
//     where the streets meet), else it starts a new node.
//  3. Visits: every pass of the trajectory within `fuse_distance_m` of a node (closest point of the pass,
//     on the keyframe polyline) is a visit of it; edges join consecutive visits along the trajectory, with
//     the arc length between them; a pair of nodes joined on several passes keeps its shortest edge.
//  4. Streets (when given, e.g. from OpenStreetMap): each edge is labelled with the street it follows, the
//  one
//     whose polyline lies within `street_max_distance_m` of more than half of the edge's polyline (sampled
//     every 2 m); the most covering one when several do; none when no street does.
// Several drives one after another (FramePosition::segment, a merged map's sessions) are kept apart: turn
// windows stay within a drive, and neither a pass nor an edge spans the step from one drive to the next.
// Edges are traversable both ways (a person walks back; streets are taken as two-way).

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geo/georeference.h"
#include "semslam/landmarks/landmark_map.h"

namespace semslam {

enum class TurnDirection { kStraight, kLeft, kRight, kUTurn };
std::string_view TurnDirectionName(TurnDirection direction);  // "straight", "left", "right", "u-turn"
// Signed angle (degrees, + = left) -> direction: |a| < straight_below_deg straight, > 150 u-turn.
TurnDirection ClassifyTurn(double signed_angle_deg, double straight_below_deg);

struct TopologyOptions {
  double turn_window_m = 15.0;
  double turn_threshold_deg = 50.0;
  double fuse_distance_m = 15.0;
  double landmark_max_distance_m = 100.0;
  // Routing: a heading change below this at a node is "straight on".
  double straight_below_deg = 30.0;
  // An edge runs along a street where it is within this of the street's centreline: half a wide street's
  // carriageway (a lane is 3-4 m from the centre line) plus the georeference's and the map's errors.
  double street_max_distance_m = 10.0;

  void Check() const;
};

struct TopoNode {
  int id = 0;
  bool is_landmark = false;
  bool is_turn = false;
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();  // on the trajectory
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();
  Wgs84 wgs84;
  std::vector<int> landmarks;                     // indices into TopologicalMap::landmarks
  TurnDirection turn = TurnDirection::kStraight;  // of the turn events here (majority), when is_turn
  double turn_angle_deg = 0.0;  // mean signed heading change of the events of `turn` (+ left)
  int turn_events = 0;          // turn events fused here
  // Of them: left, right, and turning around (|heading change| > 150 deg); a crossroads may be turned
  // different ways on different passes. `turn` is the most frequent (ties: left, right, u-turn).
  int left_turns = 0, right_turns = 0, u_turns = 0;
  int anchor_keyframe = -1;          // index into TopologicalMap::keyframes
  std::vector<int> visit_keyframes;  // nearest keyframe of each pass, in trajectory order
  std::vector<double> visit_arc_m;   // arc length along the trajectory of each pass's closest point

  int passes() const { return static_cast<int>(visit_arc_m.size()); }
};

struct TopoEdge {
  int id = 0;
  int from = 0, to = 0;  // node ids, in the direction first driven
  double length_m = 0.0;
  Points3d polyline_enu;  // from -> to, along the trajectory
  int traversals = 1;     // passes along it (either direction)
  std::string street;     // the street it follows (step 4); empty: not known
};

struct TopoLandmark {
  std::string name;
  std::string category;
  Wgs84 wgs84;
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();
  int node = -1;            // -1: too far from the trajectory for a node
  double distance_m = 0.0;  // to the trajectory (its nearest keyframe), horizontal
};

struct TopoKeyframe {
  FramePosition frame;
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();
  double arc_m = 0.0;
  double heading_change_deg = 0.0;  // the turn measure of step 1 (0 where the window does not fit)
};

struct TopologicalMap {
  explicit TopologicalMap(Georeference georeference_in) : georeference(std::move(georeference_in)) {}

  Georeference georeference;
  TopologyOptions options;
  std::vector<TopoNode> nodes;
  std::vector<TopoEdge> edges;
  std::vector<TopoLandmark> landmarks;
  std::vector<TopoKeyframe> keyframes;

  // Landmark index by name: exact, else case-insensitive; nullopt when unknown.
  std::optional<int> FindLandmark(std::string_view name) const;
  std::vector<std::string> LandmarkNames() const;
  int NumLandmarkNodes() const;
  int NumTurnNodes() const;
  // Nodes passed more than once (the revisits that fused places).
  int NumRevisitedNodes() const;
  // Number of independent cycles (edges - nodes + connected components).
  int CyclomaticNumber() const;
};

// `keyframes` in trajectory order; `landmarks` from PlaceLandmarks with the same georeference; `streets`
// (WGS84, e.g. ReadStreetsOsm) name the edges, converted to ENU through the georeference.
TopologicalMap BuildTopologicalMap(const FramePositions& keyframes,
                                   const std::vector<PlacedLandmark>& landmarks,
                                   const Georeference& georeference, const TopologyOptions& options = {},
                                   const std::vector<Street>& streets = {});

// ---- Streets (topology_streets.cc) ----

struct TopoStreet {
  std::string name;
  Points3d polyline_enu;
};
std::vector<TopoStreet> StreetsToEnu(const std::vector<Street>& streets, const EnuFrame& frame);
// The street `polyline` (ENU) follows, by step 4 above; empty when none.
std::string StreetAlong(const Points3d& polyline, const std::vector<TopoStreet>& streets,
                        double max_distance_m);
// Sets every edge's `street`.
void LabelEdgeStreets(TopologicalMap& map, const std::vector<TopoStreet>& streets);

// ---- Output and input (topology_io.cc) ----

// FeatureCollection: nodes as Points and edges as LineStrings, in WGS84.
void WriteTopologyGeoJson(const std::filesystem::path& path, const TopologicalMap& map);
// GraphML (Boost.Graph): node attributes kind, name, turn, lat, lon, east, north, passes; edge length_m,
// traversals, street.
void WriteTopologyGraphml(const std::filesystem::path& path, const TopologicalMap& map);
// Graphviz DOT (Boost.Graph), with node positions in metres (neato -n).
void WriteTopologyDot(const std::filesystem::path& path, const TopologicalMap& map);
// Everything, for ReadTopologyJson (and `semslam route`).
void WriteTopologyJson(const std::filesystem::path& path, const TopologicalMap& map);
// Throws InputError naming the file and field on a malformed file.
TopologicalMap ReadTopologyJson(const std::filesystem::path& path);
// The same JSON as a string (for the map file's extra section "topology"), and its parser; `source` names
// where the text came from in error messages (e.g. "map.semslam#topology").
std::string TopologyJsonString(const TopologicalMap& map);
TopologicalMap ParseTopologyJson(const std::string& text, const std::filesystem::path& source);
// All four next to each other: DIR/topology.{geojson,graphml,dot,json}.
void WriteTopologyFiles(const std::filesystem::path& directory, const TopologicalMap& map);

}  // namespace semslam
