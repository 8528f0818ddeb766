// OpenStreetMap extracts through libosmium (kept in this file: it is heavy to compile).

#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <osmium/handler.hpp>
#include <osmium/handler/node_locations_for_ways.hpp>
#include <osmium/index/map/flex_mem.hpp>
#include <osmium/io/any_input.hpp>
#include <osmium/visitor.hpp>
#include <string_view>
#include <unordered_map>

#include "semslam/landmarks/catalogue.h"

namespace semslam {

namespace fs = std::filesystem;

void OsmLandmarkOptions::Check() const {
  Require(std::isfinite(radius_m) && radius_m > 0, "OSM landmark radius_m must be positive");
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
    if (!options_.include_streets && way.tags().has_key("highway")) return;
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
};

}  // namespace

std::vector<Landmark> KeepNearTrajectory(std::vector<Landmark> landmarks, const OsmLandmarkOptions& options) {
  options.Check();
  const TrajectoryNeighbourhood near(options.trajectory, options.radius_m);
  std::erase_if(landmarks, [&](const Landmark& l) { return !near.Near(l.position); });
  return landmarks;
}

std::vector<Landmark> ReadLandmarksOsm(const fs::path& file, const OsmLandmarkOptions& options) {
  options.Check();
  if (!fs::is_regular_file(file)) throw InputError(file, "cannot open the OpenStreetMap file");
  std::vector<Landmark> landmarks;
  try {
    using Index = osmium::index::map::FlexMem<osmium::unsigned_object_id_type, osmium::Location>;
    Index index;
    osmium::handler::NodeLocationsForWays<Index> locations(index);
    locations.ignore_errors();  // ways whose nodes lie outside the extract
    LandmarkHandler handler(file, options, landmarks);
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
  return landmarks;
}

}  // namespace semslam
