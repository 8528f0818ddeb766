// Topological map files: GeoJSON, GraphML and DOT (Boost.Graph writers), the full-fidelity topology.json and
// its reader, and route GeoJSON. nlohmann_json stays in this file.

#include <fmt/format.h>

#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/graphml.hpp>
#include <boost/graph/graphviz.hpp>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/topology/routing.h"
#include "semslam/topology/topological_map.h"

namespace semslam {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr int kTopologyVersion = 1;

json Vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json LonLatAlt(const Wgs84& p) { return json::array({p.longitude_deg, p.latitude_deg, p.altitude_m}); }

std::string NodeKind(const TopoNode& n) {
  if (n.is_landmark && n.is_turn) return "landmark+turn";
  if (n.is_landmark) return "landmark";
  if (n.is_turn) return "turn";
  return "place";
}

std::string NodeNames(const TopologicalMap& map, const TopoNode& n) {
  std::string names;
  for (const int l : n.landmarks)
    names += (names.empty() ? "" : " / ") + map.landmarks[static_cast<size_t>(l)].name;
  return names;
}

std::string NodeLabel(const TopologicalMap& map, const TopoNode& n) {
  std::string label = NodeNames(map, n);
  if (n.is_turn) {
    label += (label.empty() ? "" : "\n") +
             fmt::format("turn {} ({:+.0f} deg)", TurnDirectionName(n.turn), n.turn_angle_deg);
  }
  return label.empty() ? fmt::format("node {}", n.id) : label;
}

// ---- Reading with located errors ----

class JsonReader {
 public:
  explicit JsonReader(fs::path file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const std::string& field, const std::string& message) const {
    throw InputError(SourceLocation{file_, 0}, field, message);
  }
  const json& Member(const json& object, const std::string& key, const std::string& path) const {
    if (!object.is_object()) Fail(path, "expected an object");
    const auto it = object.find(key);
    if (it == object.end()) Fail(Join(path, key), "missing");
    return *it;
  }
  double Number(const json& object, const std::string& key, const std::string& path) const {
    const json& v = Member(object, key, path);
    if (!v.is_number() || !std::isfinite(v.get<double>())) Fail(Join(path, key), "expected a finite number");
    return v.get<double>();
  }
  long long Integer(const json& object, const std::string& key, const std::string& path) const {
    const json& v = Member(object, key, path);
    if (!v.is_number_integer()) Fail(Join(path, key), "expected an integer");
    return v.get<long long>();
  }
  bool Bool(const json& object, const std::string& key, const std::string& path) const {
    const json& v = Member(object, key, path);
    if (!v.is_boolean()) Fail(Join(path, key), "expected true or false");
    return v.get<bool>();
  }
  std::string String(const json& object, const std::string& key, const std::string& path) const {
    const json& v = Member(object, key, path);
    if (!v.is_string()) Fail(Join(path, key), "expected a string");
    return v.get<std::string>();
  }
  const json& Array(const json& object, const std::string& key, const std::string& path) const {
    const json& v = Member(object, key, path);
    if (!v.is_array()) Fail(Join(path, key), "expected an array");
    return v;
  }
  Eigen::Vector3d Vector(const json& v, const std::string& path) const {
    if (!v.is_array() || v.size() != 3) Fail(path, "expected [x, y, z]");
    Eigen::Vector3d out;
    for (int i = 0; i < 3; ++i) {
      if (!v[static_cast<size_t>(i)].is_number() || !std::isfinite(v[static_cast<size_t>(i)].get<double>())) {
        Fail(fmt::format("{}[{}]", path, i), "expected a finite number");
      }
      out[i] = v[static_cast<size_t>(i)].get<double>();
    }
    return out;
  }
  Eigen::Vector3d Vector(const json& object, const std::string& key, const std::string& path) const {
    return Vector(Member(object, key, path), Join(path, key));
  }
  static std::string Join(const std::string& path, const std::string& key) {
    return path.empty() ? key : path + "." + key;
  }

 private:
  fs::path file_;
};

TurnDirection TurnFromName(const std::string& name, const JsonReader& r, const std::string& field) {
  for (const TurnDirection d :
       {TurnDirection::kStraight, TurnDirection::kLeft, TurnDirection::kRight, TurnDirection::kUTurn}) {
    if (TurnDirectionName(d) == name) return d;
  }
  r.Fail(field, fmt::format("unknown turn direction '{}'", name));
}

}  // namespace

std::string TopologyJsonString(const TopologicalMap& map) {
  const Sim3d& t = map.georeference.enu_from_map;
  const Wgs84& origin = map.georeference.enu_frame.origin();
  json root;
  root["format"] = "semslam-topology";
  root["version"] = kTopologyVersion;
  root["georeference"] = {
      {"origin", {{"lat", origin.latitude_deg}, {"lon", origin.longitude_deg}, {"alt", origin.altitude_m}}},
      {"enu_from_map",
       {{"scale", t.scale},
        {"rotation_wxyz", {t.rotation.w(), t.rotation.x(), t.rotation.y(), t.rotation.z()}},
        {"translation", Vec(t.translation)}}}};
  const TopologyOptions& o = map.options;
  root["options"] = {{"turn_window_m", o.turn_window_m},
                     {"turn_threshold_deg", o.turn_threshold_deg},
                     {"fuse_distance_m", o.fuse_distance_m},
                     {"landmark_max_distance_m",
                      std::isfinite(o.landmark_max_distance_m) ? o.landmark_max_distance_m : 1e300},
                     {"straight_below_deg", o.straight_below_deg},
                     {"street_max_distance_m", o.street_max_distance_m}};
  json landmarks = json::array();
  for (const TopoLandmark& l : map.landmarks) {
    landmarks.push_back({{"name", l.name},
                         {"category", l.category},
                         {"lat", l.wgs84.latitude_deg},
                         {"lon", l.wgs84.longitude_deg},
                         {"alt", l.wgs84.altitude_m},
                         {"enu", Vec(l.enu)},
                         {"map_xyz", Vec(l.map_position)},
                         {"node", l.node},
                         {"distance_m", l.distance_m}});
  }
  root["landmarks"] = landmarks;
  json nodes = json::array();
  for (const TopoNode& n : map.nodes) {
    nodes.push_back({{"id", n.id},
                     {"kind", NodeKind(n)},
                     {"is_landmark", n.is_landmark},
                     {"is_turn", n.is_turn},
                     {"enu", Vec(n.enu)},
                     {"map_xyz", Vec(n.map_position)},
                     {"lat", n.wgs84.latitude_deg},
                     {"lon", n.wgs84.longitude_deg},
                     {"alt", n.wgs84.altitude_m},
                     {"landmarks", n.landmarks},
                     {"turn", TurnDirectionName(n.turn)},
                     {"turn_angle_deg", n.turn_angle_deg},
                     {"turn_events", n.turn_events},
                     {"left_turns", n.left_turns},
                     {"right_turns", n.right_turns},
                     {"u_turns", n.u_turns},
                     {"anchor_keyframe", n.anchor_keyframe},
                     {"visit_keyframes", n.visit_keyframes},
                     {"visit_arc_m", n.visit_arc_m}});
  }
  root["nodes"] = nodes;
  json edges = json::array();
  for (const TopoEdge& e : map.edges) {
    json polyline = json::array();
    for (const Eigen::Vector3d& p : e.polyline_enu) polyline.push_back(Vec(p));
    edges.push_back({{"id", e.id},
                     {"from", e.from},
                     {"to", e.to},
                     {"length_m", e.length_m},
                     {"traversals", e.traversals},
                     {"street", e.street},
                     {"polyline_enu", polyline}});
  }
  root["edges"] = edges;
  json keyframes = json::array();
  for (const TopoKeyframe& k : map.keyframes) {
    keyframes.push_back({{"frame_index", k.frame.frame_index},
                         {"keyframe_id", k.frame.keyframe_id},
                         {"timestamp", k.frame.timestamp},
                         {"map_xyz", Vec(k.frame.map_position)},
                         {"enu", Vec(k.enu)},
                         {"arc_m", k.arc_m},
                         {"heading_change_deg", k.heading_change_deg}});
  }
  root["keyframes"] = keyframes;
  return root.dump(1) + "\n";
}

void WriteTopologyJson(const fs::path& path, const TopologicalMap& map) {
  WriteFileAtomically(path, TopologyJsonString(map));
}

TopologicalMap ReadTopologyJson(const fs::path& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream) throw InputError(path, "cannot open the topology file");
  std::stringstream buffer;
  buffer << stream.rdbuf();
  return ParseTopologyJson(buffer.str(), path);
}

TopologicalMap ParseTopologyJson(const std::string& text, const fs::path& path) {
  json root;
  try {
    root = json::parse(text);
  } catch (const json::parse_error& e) {
    const size_t byte = std::min<size_t>(e.byte, text.size());
    const int line = 1 + static_cast<int>(std::count(text.begin(),
                                                     text.begin() + static_cast<std::ptrdiff_t>(byte), '\n'));
    throw InputError(SourceLocation{path, line}, "json", e.what());
  }
  const JsonReader r(path);
  if (!root.is_object() || root.value("format", std::string()) != "semslam-topology") {
    r.Fail("format", "not a semslam topology file (expected \"format\": \"semslam-topology\")");
  }
  const long long version = r.Integer(root, "version", "");
  if (version != kTopologyVersion) r.Fail("version", fmt::format("unsupported version {}", version));

  const json& geo = r.Member(root, "georeference", "");
  const json& origin_json = r.Member(geo, "origin", "georeference");
  const Wgs84 origin{r.Number(origin_json, "lat", "georeference.origin"),
                     r.Number(origin_json, "lon", "georeference.origin"),
                     r.Number(origin_json, "alt", "georeference.origin")};
  if (!origin.IsValid()) r.Fail("georeference.origin", "not a valid WGS84 position");
  const json& t = r.Member(geo, "enu_from_map", "georeference");
  const double scale = r.Number(t, "scale", "georeference.enu_from_map");
  if (!(scale > 0)) r.Fail("georeference.enu_from_map.scale", "must be positive");
  const json& q = r.Array(t, "rotation_wxyz", "georeference.enu_from_map");
  if (q.size() != 4) r.Fail("georeference.enu_from_map.rotation_wxyz", "expected 4 numbers");
  for (size_t i = 0; i < 4; ++i) {
    if (!q[i].is_number())
      r.Fail(fmt::format("georeference.enu_from_map.rotation_wxyz[{}]", i), "expected a number");
  }
  const Eigen::Quaterniond rotation(q[0].get<double>(), q[1].get<double>(), q[2].get<double>(),
                                    q[3].get<double>());
  if (!(rotation.norm() > 0.5))
    r.Fail("georeference.enu_from_map.rotation_wxyz", "not a rotation quaternion");
  TopologicalMap map(Georeference(
      EnuFrame(origin), Sim3d(scale, rotation, r.Vector(t, "translation", "georeference.enu_from_map"))));

  const json& o = r.Member(root, "options", "");
  map.options.turn_window_m = r.Number(o, "turn_window_m", "options");
  map.options.turn_threshold_deg = r.Number(o, "turn_threshold_deg", "options");
  map.options.fuse_distance_m = r.Number(o, "fuse_distance_m", "options");
  map.options.landmark_max_distance_m = r.Number(o, "landmark_max_distance_m", "options");
  map.options.straight_below_deg = r.Number(o, "straight_below_deg", "options");
  if (o.contains("street_max_distance_m"))  // not in files written before edges named streets
    map.options.street_max_distance_m = r.Number(o, "street_max_distance_m", "options");
  try {
    map.options.Check();
  } catch (const InvalidArgument& e) {
    r.Fail("options", e.what());
  }

  const json& landmarks = r.Array(root, "landmarks", "");
  const json& nodes = r.Array(root, "nodes", "");
  const json& edges = r.Array(root, "edges", "");
  const json& keyframes = r.Array(root, "keyframes", "");
  const auto check_index = [&](long long value, size_t size, const std::string& field, bool allow_none) {
    if ((allow_none && value == -1) || (value >= 0 && static_cast<size_t>(value) < size))
      return static_cast<int>(value);
    r.Fail(field, size == 0 ? fmt::format("index {}, but there is none to refer to", value)
                            : fmt::format("index {} out of range (0..{})", value, size - 1));
  };

  for (size_t i = 0; i < landmarks.size(); ++i) {
    const std::string p = fmt::format("landmarks[{}]", i);
    const json& j = landmarks[i];
    TopoLandmark l;
    l.name = r.String(j, "name", p);
    if (l.name.empty()) r.Fail(p + ".name", "empty landmark name");
    l.category = r.String(j, "category", p);
    l.wgs84 = Wgs84{r.Number(j, "lat", p), r.Number(j, "lon", p), r.Number(j, "alt", p)};
    if (!l.wgs84.IsValid()) r.Fail(p, "not a valid WGS84 position");
    l.enu = r.Vector(j, "enu", p);
    l.map_position = r.Vector(j, "map_xyz", p);
    l.node = check_index(r.Integer(j, "node", p), nodes.size(), p + ".node", true);
    l.distance_m = r.Number(j, "distance_m", p);
    map.landmarks.push_back(std::move(l));
  }
  for (size_t i = 0; i < nodes.size(); ++i) {
    const std::string p = fmt::format("nodes[{}]", i);
    const json& j = nodes[i];
    TopoNode n;
    n.id = static_cast<int>(r.Integer(j, "id", p));
    if (n.id != static_cast<int>(i))
      r.Fail(p + ".id", fmt::format("expected {} (nodes are numbered in order)", i));
    n.is_landmark = r.Bool(j, "is_landmark", p);
    n.is_turn = r.Bool(j, "is_turn", p);
    n.enu = r.Vector(j, "enu", p);
    n.map_position = r.Vector(j, "map_xyz", p);
    n.wgs84 = Wgs84{r.Number(j, "lat", p), r.Number(j, "lon", p), r.Number(j, "alt", p)};
    if (!n.wgs84.IsValid()) r.Fail(p, "not a valid WGS84 position");
    const json& ls = r.Array(j, "landmarks", p);
    for (size_t k = 0; k < ls.size(); ++k) {
      if (!ls[k].is_number_integer()) r.Fail(fmt::format("{}.landmarks[{}]", p, k), "expected an integer");
      n.landmarks.push_back(check_index(ls[k].get<long long>(), map.landmarks.size(),
                                        fmt::format("{}.landmarks[{}]", p, k), false));
    }
    n.turn = TurnFromName(r.String(j, "turn", p), r, p + ".turn");
    n.turn_angle_deg = r.Number(j, "turn_angle_deg", p);
    n.turn_events = static_cast<int>(r.Integer(j, "turn_events", p));
    n.left_turns = static_cast<int>(r.Integer(j, "left_turns", p));
    n.right_turns = static_cast<int>(r.Integer(j, "right_turns", p));
    n.u_turns = static_cast<int>(r.Integer(j, "u_turns", p));
    if (n.left_turns < 0 || n.right_turns < 0 || n.u_turns < 0 ||
        n.left_turns + n.right_turns + n.u_turns != n.turn_events) {
      r.Fail(p + ".turn_events", "must be left_turns + right_turns + u_turns");
    }
    n.anchor_keyframe =
        check_index(r.Integer(j, "anchor_keyframe", p), keyframes.size(), p + ".anchor_keyframe", true);
    const json& vk = r.Array(j, "visit_keyframes", p);
    const json& va = r.Array(j, "visit_arc_m", p);
    if (vk.size() != va.size()) r.Fail(p + ".visit_arc_m", "must have as many entries as visit_keyframes");
    for (size_t k = 0; k < vk.size(); ++k) {
      if (!vk[k].is_number_integer() || !va[k].is_number())
        r.Fail(fmt::format("{}.visits[{}]", p, k), "expected numbers");
      n.visit_keyframes.push_back(check_index(vk[k].get<long long>(), keyframes.size(),
                                              fmt::format("{}.visit_keyframes[{}]", p, k), false));
      n.visit_arc_m.push_back(va[k].get<double>());
    }
    map.nodes.push_back(std::move(n));
  }
  for (size_t i = 0; i < edges.size(); ++i) {
    const std::string p = fmt::format("edges[{}]", i);
    const json& j = edges[i];
    TopoEdge e;
    e.id = static_cast<int>(r.Integer(j, "id", p));
    if (e.id != static_cast<int>(i))
      r.Fail(p + ".id", fmt::format("expected {} (edges are numbered in order)", i));
    e.from = check_index(r.Integer(j, "from", p), nodes.size(), p + ".from", false);
    e.to = check_index(r.Integer(j, "to", p), nodes.size(), p + ".to", false);
    e.length_m = r.Number(j, "length_m", p);
    if (e.length_m < 0) r.Fail(p + ".length_m", "must not be negative");
    e.traversals = static_cast<int>(r.Integer(j, "traversals", p));
    if (j.contains("street")) e.street = r.String(j, "street", p);  // optional: older files have none
    const json& line = r.Array(j, "polyline_enu", p);
    if (line.size() < 2) r.Fail(p + ".polyline_enu", "needs at least 2 points");
    for (size_t k = 0; k < line.size(); ++k)
      e.polyline_enu.push_back(r.Vector(line[k], fmt::format("{}.polyline_enu[{}]", p, k)));
    map.edges.push_back(std::move(e));
  }
  for (size_t i = 0; i < keyframes.size(); ++i) {
    const std::string p = fmt::format("keyframes[{}]", i);
    const json& j = keyframes[i];
    TopoKeyframe k;
    const long long frame_index = r.Integer(j, "frame_index", p);
    if (frame_index < 0) r.Fail(p + ".frame_index", "must not be negative");
    k.frame.frame_index = static_cast<size_t>(frame_index);
    k.frame.keyframe_id = r.Integer(j, "keyframe_id", p);
    k.frame.timestamp = r.Number(j, "timestamp", p);
    k.frame.map_position = r.Vector(j, "map_xyz", p);
    k.enu = r.Vector(j, "enu", p);
    k.arc_m = r.Number(j, "arc_m", p);
    k.heading_change_deg = r.Number(j, "heading_change_deg", p);
    map.keyframes.push_back(k);
  }
  return map;
}

void WriteTopologyGeoJson(const fs::path& path, const TopologicalMap& map) {
  const EnuFrame& frame = map.georeference.enu_frame;
  json features = json::array();
  for (const TopoNode& n : map.nodes) {
    json names = json::array();
    for (const int l : n.landmarks) names.push_back(map.landmarks[static_cast<size_t>(l)].name);
    json properties = {{"feature", "node"},  {"id", n.id},           {"kind", NodeKind(n)},
                       {"landmarks", names}, {"passes", n.passes()}, {"label", NodeLabel(map, n)}};
    if (n.is_turn) {
      properties["turn"] = TurnDirectionName(n.turn);
      properties["turn_angle_deg"] = n.turn_angle_deg;
    }
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "Point"}, {"coordinates", LonLatAlt(n.wgs84)}}},
                        {"properties", properties}});
  }
  for (const TopoEdge& e : map.edges) {
    json coordinates = json::array();
    for (const Eigen::Vector3d& p : e.polyline_enu) coordinates.push_back(LonLatAlt(frame.ToWgs84(p)));
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "LineString"}, {"coordinates", coordinates}}},
                        {"properties",
                         {{"feature", "edge"},
                          {"id", e.id},
                          {"from", e.from},
                          {"to", e.to},
                          {"length_m", e.length_m},
                          {"traversals", e.traversals},
                          {"street", e.street}}}});
  }
  for (const TopoLandmark& l : map.landmarks) {
    features.push_back({{"type", "Feature"},
                        {"geometry", {{"type", "Point"}, {"coordinates", LonLatAlt(l.wgs84)}}},
                        {"properties",
                         {{"feature", "landmark"},
                          {"name", l.name},
                          {"category", l.category},
                          {"node", l.node},
                          {"distance_m", l.distance_m}}}});
  }
  WriteFileAtomically(path, json({{"type", "FeatureCollection"}, {"features", features}}).dump(1) + "\n");
}

namespace {

struct VertexProperties {
  std::string kind, name, label, turn, pos;
  double lat = 0, lon = 0, east = 0, north = 0;
  int passes = 0;
};
struct EdgeProperties {
  double length_m = 0;
  int traversals = 0;
  std::string street, label;
};
using OutputGraph =
    boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, VertexProperties, EdgeProperties>;

OutputGraph MakeOutputGraph(const TopologicalMap& map) {
  OutputGraph g(map.nodes.size());
  for (const TopoNode& n : map.nodes) {
    VertexProperties& v = g[static_cast<size_t>(n.id)];
    v.kind = NodeKind(n);
    v.name = NodeNames(map, n);
    v.label = NodeLabel(map, n);
    v.turn = n.is_turn ? std::string(TurnDirectionName(n.turn)) : std::string();
    v.lat = n.wgs84.latitude_deg;
    v.lon = n.wgs84.longitude_deg;
    v.east = n.enu.x();
    v.north = n.enu.y();
    v.passes = n.passes();
    v.pos = fmt::format("{:.1f},{:.1f}!", n.enu.x(), n.enu.y());
  }
  for (const TopoEdge& e : map.edges) {
    boost::add_edge(static_cast<size_t>(e.from), static_cast<size_t>(e.to),
                    EdgeProperties{e.length_m, e.traversals, e.street,
                                   e.street.empty() ? fmt::format("{:.0f} m", e.length_m)
                                                    : fmt::format("{}, {:.0f} m", e.street, e.length_m)},
                    g);
  }
  return g;
}

}  // namespace

void WriteTopologyGraphml(const fs::path& path, const TopologicalMap& map) {
  OutputGraph g = MakeOutputGraph(map);
  boost::dynamic_properties dp;
  dp.property("kind", boost::get(&VertexProperties::kind, g));
  dp.property("name", boost::get(&VertexProperties::name, g));
  dp.property("turn", boost::get(&VertexProperties::turn, g));
  dp.property("lat", boost::get(&VertexProperties::lat, g));
  dp.property("lon", boost::get(&VertexProperties::lon, g));
  dp.property("east_m", boost::get(&VertexProperties::east, g));
  dp.property("north_m", boost::get(&VertexProperties::north, g));
  dp.property("passes", boost::get(&VertexProperties::passes, g));
  dp.property("length_m", boost::get(&EdgeProperties::length_m, g));
  dp.property("traversals", boost::get(&EdgeProperties::traversals, g));
  dp.property("street", boost::get(&EdgeProperties::street, g));
  std::ostringstream out;
  out.precision(10);
  boost::write_graphml(out, g, dp, true);
  WriteFileAtomically(path, out.str());
}

void WriteTopologyDot(const fs::path& path, const TopologicalMap& map) {
  OutputGraph g = MakeOutputGraph(map);
  boost::dynamic_properties dp;
  dp.property("node_id", boost::get(boost::vertex_index, g));
  dp.property("label", boost::get(&VertexProperties::label, g));
  dp.property("kind", boost::get(&VertexProperties::kind, g));
  dp.property("pos", boost::get(&VertexProperties::pos, g));
  dp.property("label", boost::get(&EdgeProperties::label, g));
  std::ostringstream out;
  boost::write_graphviz_dp(out, g, dp);
  WriteFileAtomically(path, out.str());
}

void WriteTopologyFiles(const fs::path& directory, const TopologicalMap& map) {
  WriteTopologyGeoJson(directory / "topology.geojson", map);
  WriteTopologyGraphml(directory / "topology.graphml", map);
  WriteTopologyDot(directory / "topology.dot", map);
  WriteTopologyJson(directory / "topology.json", map);
}

void WriteRouteGeoJson(const fs::path& path, const TopologicalMap& map, const Route& route) {
  const EnuFrame& frame = map.georeference.enu_frame;
  json coordinates = json::array();
  for (const Eigen::Vector3d& p : route.polyline_enu) coordinates.push_back(LonLatAlt(frame.ToWgs84(p)));
  json steps = json::array();
  for (const RouteStep& s : route.steps) {
    static const char* kKinds[] = {"start", "drive", "turn", "arrive"};
    json step = {{"kind", kKinds[static_cast<int>(s.kind)]}, {"text", s.text}, {"node", s.node}};
    if (s.kind == RouteStep::Kind::kDrive) step["distance_m"] = s.distance_m;
    if (s.kind == RouteStep::Kind::kTurn) step["turn"] = TurnDirectionName(s.turn);
    steps.push_back(step);
  }
  const auto name = [&](int landmark) {
    return landmark >= 0 ? json(map.landmarks[static_cast<size_t>(landmark)].name) : json(nullptr);
  };
  json features = json::array();
  features.push_back({{"type", "Feature"},
                      {"geometry", {{"type", "LineString"}, {"coordinates", coordinates}}},
                      {"properties",
                       {{"feature", "route"},
                        {"from", name(route.from_landmark)},
                        {"to", name(route.to_landmark)},
                        {"length_m", route.length_m},
                        {"nodes", route.nodes},
                        {"edges", route.edges},
                        {"steps", steps}}}});
  for (size_t i = 0; i < route.nodes.size(); ++i) {
    const TopoNode& n = map.nodes[static_cast<size_t>(route.nodes[i])];
    features.push_back(
        {{"type", "Feature"},
         {"geometry", {{"type", "Point"}, {"coordinates", LonLatAlt(n.wgs84)}}},
         {"properties",
          {{"feature", "route_node"}, {"order", i}, {"id", n.id}, {"label", NodeLabel(map, n)}}}});
  }
  WriteFileAtomically(path, json({{"type", "FeatureCollection"}, {"features", features}}).dump(1) + "\n");
}

}  // namespace semslam
