// OpenStreetMap extracts through libosmium (kept in this file: it is heavy to compile).

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>
#include <osmium/handler.hpp>
#include <osmium/handler/node_locations_for_ways.hpp>
#include <osmium/index/map/flex_mem.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/visitor.hpp>
#include <string_view>
#include <unordered_map>

#include "semslam/core/utf8.h"
#include "semslam/landmarks/catalogue.h"

namespace semslam {

namespace fs = std::filesystem;

void OsmLandmarkOptions::Check() const {
  Require(std::isfinite(radius_m) && radius_m > 0, "OSM landmark radius_m must be positive");
  Require(std::isfinite(corner_radius_m) && corner_radius_m > 0, "OSM corner_radius_m must be positive");
  Require(std::isfinite(corner_merge_m) && corner_merge_m >= 0, "OSM corner_merge_m must not be negative");
  for (const Wgs84& p : trajectory) Require(p.IsValid(), "OSM landmark trajectory has an invalid position");
}

namespace {

// Tags that make a named object a landmark, in order of preference for its category.
constexpr std::string_view kCategoryKeys[] = {
    "amenity",          "tourism", "historic", "shop",    "leisure", "office",  "building",
    "public_transport", "railway", "man_made", "natural", "place",   "landuse", "highway"};

bool IsNameKey(std::string_view key) {
  return key == "name" || key.rfind("name:", 0) == 0 || key == "alt_name" || key == "old_name" ||
         key == "official_name" || key == "short_name" || key == "loc_name" || key == "int_name" ||
         key.rfind("source", 0) == 0 || key == "created_by" || key == "note" || key == "fixme";
}

std::string Category(const osmium::TagList& tags) {
  for (const std::string_view key : kCategoryKeys) {
    if (const char* value = tags.get_value_by_key(std::string(key).c_str()))
      return fmt::format("{}={}", key, value);
  }
  return {};
}

bool HasNonNameTag(const osmium::TagList& tags) {
  for (const osmium::Tag& tag : tags) {
    if (!IsNameKey(tag.key())) return true;
  }
  return false;
}

// Horizontal distance test against the trajectory, on a grid of radius-sized cells in a local tangent plane.
class TrajectoryNeighbourhood {
 public:
  TrajectoryNeighbourhood(const std::vector<Wgs84>& trajectory, double radius_m) : radius_m_(radius_m) {
    if (trajectory.empty()) return;
    frame_.emplace(trajectory.front());
    Eigen::Vector2d previous;
    for (size_t i = 0; i < trajectory.size(); ++i) {
      const Eigen::Vector2d p = frame_->ToEnu(trajectory[i]).head<2>();
      if (i > 0) {
        // Densify so that no point of the path is farther than radius/4 from a stored point.
        const double step = radius_m_ / 4.0;
        const int n = static_cast<int>(std::ceil((p - previous).norm() / step));
        for (int k = 1; k < n; ++k) Insert(previous + (p - previous) * (static_cast<double>(k) / n));
      }
      Insert(p);
      previous = p;
    }
  }

  // True when there is no trajectory (no filter) or the position is within the radius of it.
  bool Near(const Wgs84& position) const {
    if (!frame_) return true;
    const Eigen::Vector2d p = frame_->ToEnu(position).head<2>();
    const auto [cx, cy] = Cell(p);
    for (long long dx = -1; dx <= 1; ++dx) {
      for (long long dy = -1; dy <= 1; ++dy) {
        const auto it = cells_.find(Key(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (const Eigen::Vector2d& q : it->second) {
          if ((q - p).squaredNorm() <= radius_m_ * radius_m_) return true;
        }
      }
    }
    return false;
  }

  // Whether some point of the polyline (sampled every radius/4) is near.
  bool NearPolyline(const std::vector<Wgs84>& polyline) const {
    if (!frame_) return true;
    for (size_t i = 0; i < polyline.size(); ++i) {
      if (Near(polyline[i])) return true;
      if (i + 1 == polyline.size()) break;
      const Eigen::Vector3d a = frame_->ToEnu(polyline[i]), b = frame_->ToEnu(polyline[i + 1]);
      const int n = static_cast<int>(std::ceil((b - a).head<2>().norm() / (radius_m_ / 4.0)));
      for (int k = 1; k < n; ++k) {
        if (Near(frame_->ToWgs84(a + (b - a) * (static_cast<double>(k) / n)))) return true;
      }
    }
    return false;
  }

 private:
  std::pair<long long, long long> Cell(const Eigen::Vector2d& p) const {
    return {static_cast<long long>(std::floor(p.x() / radius_m_)),
            static_cast<long long>(std::floor(p.y() / radius_m_))};
  }
  static long long Key(long long x, long long y) { return x * 73856093LL ^ y * 19349663LL; }
  void Insert(const Eigen::Vector2d& p) {
    const auto [cx, cy] = Cell(p);
    cells_[Key(cx, cy)].push_back(p);
  }

  double radius_m_;
  std::optional<EnuFrame> frame_;
  std::unordered_map<long long, std::vector<Eigen::Vector2d>> cells_;
};

// The nodes of named highway=* ways, for street corners: which street names meet at a node, with how many
// arms.
class HighwayNodes {
 public:
  struct Junction {
    osmium::object_id_type node = 0;
    std::vector<std::string> names;  // distinct, in byte order
    Wgs84 position;
  };

  void Add(const osmium::Way& way, const char* name) {
    const int name_id = NameId(name);
    const osmium::WayNodeList& nodes = way.nodes();
    for (size_t i = 0; i < nodes.size(); ++i) {
      // The arms of the way at this node: towards its previous and its next node.
      const int arms = (i > 0 ? 1 : 0) + (i + 1 < nodes.size() ? 1 : 0);
      nodes_.push_back({nodes[i].ref(), name_id, arms, nodes[i].location()});
    }
  }

  // Nodes where ways of two or more names meet with three or more arms: streets that meet, not one street
  // that changes its name (even where an unnamed driveway or path leaves there).
  std::vector<Junction> Junctions() {
    std::sort(nodes_.begin(), nodes_.end(),
              [](const NodeUse& a, const NodeUse& b) { return a.node < b.node; });
    std::vector<Junction> junctions;
    for (size_t begin = 0; begin < nodes_.size();) {
      size_t end = begin;
      int arms = 0;
      std::vector<std::string> names;
      osmium::Location location;
      for (; end < nodes_.size() && nodes_[end].node == nodes_[begin].node; ++end) {
        arms += nodes_[end].arms;
        names.push_back(names_[static_cast<size_t>(nodes_[end].name)]);
        if (nodes_[end].location.valid()) location = nodes_[end].location;
      }
      std::sort(names.begin(), names.end());
      names.erase(std::unique(names.begin(), names.end()), names.end());
      if (names.size() >= 2 && arms >= 3 && location.valid()) {
        junctions.push_back(
            {nodes_[begin].node, std::move(names), Wgs84{location.lat(), location.lon(), 0.0}});
      }
      begin = end;
    }
    return junctions;
  }

 private:
  struct NodeUse {
    osmium::object_id_type node;
    int name;  // into names_
    int arms;
    osmium::Location location;  // invalid outside the extract
  };

  int NameId(const char* name) {
    const auto [it, inserted] = name_ids_.try_emplace(name, static_cast<int>(names_.size()));
    if (inserted) names_.emplace_back(name);
    return it->second;
  }

  std::vector<NodeUse> nodes_;
  std::vector<std::string> names_;
  std::unordered_map<std::string, int> name_ids_;
};

// Junctions of the same names whose nodes chain within merge_m become one corner, at their nodes' mean.
std::vector<Landmark> MergeCorners(const std::vector<HighwayNodes::Junction>& junctions, double merge_m,
                                   const fs::path& file) {
  std::map<std::vector<std::string>, std::vector<const HighwayNodes::Junction*>> by_names;
  for (const HighwayNodes::Junction& j : junctions) by_names[j.names].push_back(&j);
  std::vector<Landmark> corners;
  for (const auto& [names, group] : by_names) {
    const EnuFrame frame(group.front()->position);
    std::vector<Eigen::Vector2d> enu;
    for (const HighwayNodes::Junction* j : group) enu.push_back(frame.ToEnu(j->position).head<2>());
    // Single linkage: union-find over the pairs closer than merge_m.
    std::vector<size_t> parent(group.size());
    std::iota(parent.begin(), parent.end(), size_t{0});
    const auto root = [&](size_t i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    for (size_t a = 0; a < group.size(); ++a) {
      for (size_t b = a + 1; b < group.size(); ++b) {
        if ((enu[a] - enu[b]).norm() <= merge_m) parent[root(b)] = root(a);
      }
    }
    std::map<osmium::object_id_type, std::vector<size_t>> clusters;  // by lowest node id
    std::map<size_t, osmium::object_id_type> lowest_of_root;
    for (size_t i = 0; i < group.size(); ++i) {
      const auto [it, inserted] = lowest_of_root.try_emplace(root(i), group[i]->node);
      if (!inserted) it->second = std::min(it->second, group[i]->node);
    }
    for (size_t i = 0; i < group.size(); ++i) clusters[lowest_of_root[root(i)]].push_back(i);
    std::string name;
    for (const std::string& n : names) name += (name.empty() ? "" : " / ") + n;
    for (const auto& [lowest, members] : clusters) {
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (const size_t i : members) mean.head<2>() += enu[i];
      mean /= static_cast<double>(members.size());
      Landmark corner;
      corner.name = name;
      corner.position = frame.ToWgs84(mean);
      corner.position.altitude_m = 0.0;
      corner.category = std::string(kCornerCategory);
      corner.source = SourceLocation{fs::path(file.string() + fmt::format("#node/{}", lowest)), 0};
      corners.push_back(std::move(corner));
    }
  }
  return corners;
}

class LandmarkHandler : public osmium::handler::Handler {
 public:
  LandmarkHandler(const fs::path& file, const OsmLandmarkOptions& options, std::vector<Landmark>& out)
      : file_(file), options_(options), near_(options.trajectory, options.radius_m), out_(out) {}

  void node(const osmium::Node& node) {
    const char* name = node.tags().get_value_by_key("name");
    if (name == nullptr || *name == '\0') return;
    if (!options_.include_untagged_nodes && !HasNonNameTag(node.tags())) return;
    if (!node.location().valid()) {
      throw InputError(SourceLocation{file_, 0}, fmt::format("node/{}", node.id()),
                       "named node without a valid location");
    }
    Add(name, Wgs84{node.location().lat(), node.location().lon(), 0.0}, Category(node.tags()),
        fmt::format("node/{}", node.id()));
  }

  void way(const osmium::Way& way) {
    const char* name = way.tags().get_value_by_key("name");
    if (name == nullptr || *name == '\0') return;
    const bool highway = way.tags().has_key("highway");
    if (highway && options_.include_corners) highway_nodes_.Add(way, name);
    if (!options_.include_streets && highway) return;
    const osmium::WayNodeList& nodes = way.nodes();
    double lat = 0, lon = 0;
    int count = 0;
    const size_t n = nodes.size() > 1 && way.is_closed() ? nodes.size() - 1 : nodes.size();
    for (size_t i = 0; i < n; ++i) {
      const osmium::Location& location = nodes[i].location();
      if (!location.valid()) continue;
      lat += location.lat();
      lon += location.lon();
      ++count;
    }
    if (count == 0) return;  // none of its nodes is in the extract
    Add(name, Wgs84{lat / count, lon / count, 0.0}, Category(way.tags()), fmt::format("way/{}", way.id()));
  }

  // After the whole file: the street corners near the trajectory.
  void AddCorners() {
    if (!options_.include_corners) return;
    const TrajectoryNeighbourhood near_corner(options_.trajectory, options_.corner_radius_m);
    for (Landmark& corner : MergeCorners(highway_nodes_.Junctions(), options_.corner_merge_m, file_)) {
      if (near_corner.Near(corner.position)) out_.push_back(std::move(corner));
    }
  }

 private:
  void Add(const char* name, const Wgs84& position, std::string category, const std::string& id) {
    if (!near_.Near(position)) return;
    Landmark landmark;
    landmark.name = name;
    landmark.position = position;
    landmark.category = std::move(category);
    landmark.source = SourceLocation{fs::path(file_.string() + "#" + id), 0};
    out_.push_back(std::move(landmark));
  }

  const fs::path& file_;
  const OsmLandmarkOptions& options_;
  TrajectoryNeighbourhood near_;
  std::vector<Landmark>& out_;
  HighwayNodes highway_nodes_;
};

class StreetHandler : public osmium::handler::Handler {
 public:
  StreetHandler(const fs::path& file, const OsmLandmarkOptions& options, std::vector<Street>& out)
      : file_(file), near_(options.trajectory, options.radius_m), out_(out) {}

  void way(const osmium::Way& way) {
    const char* highway = way.tags().get_value_by_key("highway");
    const char* name = way.tags().get_value_by_key("name");
    if (highway == nullptr || name == nullptr || *name == '\0') return;
    const SourceLocation source{fs::path(file_.string() + fmt::format("#way/{}", way.id())), 0};
    RequireUtf8(name, source, "name");
    RequireUtf8(highway, source, "highway");
    Street street{name, highway, {}, source};
    const auto flush = [&] {
      if (street.polyline.size() >= 2 && near_.NearPolyline(street.polyline)) out_.push_back(street);
      street.polyline.clear();
    };
    for (const osmium::NodeRef& node : way.nodes()) {
      if (!node.location().valid()) {
        flush();
        continue;
      }
      street.polyline.push_back(Wgs84{node.location().lat(), node.location().lon(), 0.0});
    }
    flush();
  }

 private:
  const fs::path& file_;
  TrajectoryNeighbourhood near_;
  std::vector<Street>& out_;
};

// Runs `handler` over the nodes and ways of `file`, the ways' node locations filled in; located errors.
template <typename Handler>
void ApplyToOsm(const fs::path& file, Handler& handler) {
  if (!fs::is_regular_file(file)) throw InputError(file, "cannot open the OpenStreetMap file");
  try {
    using Index = osmium::index::map::FlexMem<osmium::unsigned_object_id_type, osmium::Location>;
    Index index;
    osmium::handler::NodeLocationsForWays<Index> locations(index);
    locations.ignore_errors();  // ways whose nodes lie outside the extract
    osmium::io::Reader reader(file.string(), osmium::osm_entity_bits::node | osmium::osm_entity_bits::way);
    osmium::apply(reader, locations, handler);
    reader.close();
  } catch (const InputError&) {
    throw;
  } catch (const osmium::xml_error& e) {
    throw InputError(SourceLocation{file, static_cast<int>(e.line)}, "xml",
                     fmt::format("column {}: {}", e.column, e.error_string));
  } catch (const std::exception& e) {
    throw InputError(file, fmt::format("cannot read the OpenStreetMap extract: {}", e.what()));
  }
}

}  // namespace

std::vector<Landmark> KeepNearTrajectory(std::vector<Landmark> landmarks, const OsmLandmarkOptions& options) {
  options.Check();
  const TrajectoryNeighbourhood near(options.trajectory, options.radius_m);
  const TrajectoryNeighbourhood near_corner(options.trajectory, options.corner_radius_m);
  std::erase_if(landmarks, [&](const Landmark& l) {
    if (l.category == kCornerCategory) return !options.include_corners || !near_corner.Near(l.position);
    return !near.Near(l.position);
  });
  return landmarks;
}

std::vector<Landmark> ReadLandmarksOsm(const fs::path& file, const OsmLandmarkOptions& options) {
  options.Check();
  std::vector<Landmark> landmarks;
  LandmarkHandler handler(file, options, landmarks);
  ApplyToOsm(file, handler);
  handler.AddCorners();
  return landmarks;
}

std::vector<Street> ReadStreetsOsm(const fs::path& file, const OsmLandmarkOptions& options) {
  options.Check();
  std::vector<Street> streets;
  StreetHandler handler(file, options, streets);
  ApplyToOsm(file, handler);
  return streets;
}

}  // namespace semslam
