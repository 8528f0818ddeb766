// Which street each edge of the topological map follows (step 4 of topological_map.h).

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "semslam/core/error.h"
#include "semslam/topology/topological_map.h"

namespace semslam {

namespace {

constexpr double kSampleStepM = 2.0;

// Points every kSampleStepM along the polyline (horizontal), both ends included.
std::vector<Eigen::Vector2d> Sample(const Points3d& polyline) {
  std::vector<Eigen::Vector2d> samples;
  if (polyline.empty()) return samples;
  samples.push_back(polyline.front().head<2>());
  double carried = 0.0;  // distance along the polyline since the last sample
  for (size_t i = 1; i < polyline.size(); ++i) {
    const Eigen::Vector2d a = polyline[i - 1].head<2>(), b = polyline[i].head<2>();
    const double length = (b - a).norm();
    double at = kSampleStepM - carried;
    for (; at <= length; at += kSampleStepM) samples.push_back(a + (b - a) * (at / length));
    carried = length - (at - kSampleStepM);
  }
  if ((samples.back() - polyline.back().head<2>()).norm() > 1e-9)
    samples.push_back(polyline.back().head<2>());
  return samples;
}

double SegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (a + t * d - p).norm();
}

struct IndexedStreet {
  const TopoStreet* street;
  Eigen::Vector2d lo, hi;  // bounding box, grown by the distance
};

}  // namespace

std::vector<TopoStreet> StreetsToEnu(const std::vector<Street>& streets, const EnuFrame& frame) {
  std::vector<TopoStreet> out;
  out.reserve(streets.size());
  for (const Street& s : streets) {
    TopoStreet t;
    t.name = s.name;
    for (const Wgs84& p : s.polyline) {
      Require(p.IsValid(), "topology: street '" + s.name + "' has an invalid position");
      t.polyline_enu.push_back(frame.ToEnu(p));
    }
    out.push_back(std::move(t));
  }
  return out;
}

std::string StreetAlong(const Points3d& polyline, const std::vector<TopoStreet>& streets,
                        double max_distance_m) {
  if (polyline.empty() || streets.empty()) return {};
  std::vector<IndexedStreet> indexed;
  for (const TopoStreet& s : streets) {
    if (s.polyline_enu.empty() || s.name.empty()) continue;
    IndexedStreet is{&s, s.polyline_enu.front().head<2>(), s.polyline_enu.front().head<2>()};
    for (const Eigen::Vector3d& p : s.polyline_enu) {
      is.lo = is.lo.cwiseMin(p.head<2>());
      is.hi = is.hi.cwiseMax(p.head<2>());
    }
    is.lo.array() -= max_distance_m;
    is.hi.array() += max_distance_m;
    indexed.push_back(is);
  }
  const std::vector<Eigen::Vector2d> samples = Sample(polyline);
  struct Cover {
    int samples = 0;
    double distance_sum = 0.0;
  };
  std::map<std::string, Cover> covers;  // by street name: ways of one street count together
  for (const Eigen::Vector2d& p : samples) {
    std::map<std::string, double> nearest;
    for (const IndexedStreet& is : indexed) {
      if ((p.array() < is.lo.array()).any() || (p.array() > is.hi.array()).any()) continue;
      const Points3d& line = is.street->polyline_enu;
      double d = line.size() == 1 ? (line[0].head<2>() - p).norm() : std::numeric_limits<double>::infinity();
      for (size_t i = 1; i < line.size(); ++i)
        d = std::min(d, SegmentDistance(p, line[i - 1].head<2>(), line[i].head<2>()));
      if (d > max_distance_m) continue;
      const auto [it, inserted] = nearest.try_emplace(is.street->name, d);
      if (!inserted) it->second = std::min(it->second, d);
    }
    for (const auto& [name, d] : nearest) {
      ++covers[name].samples;
      covers[name].distance_sum += d;
    }
  }
  // The most covering street (ties: the closer on average), if it covers more than half of the samples.
  const std::string* best = nullptr;
  const Cover* best_cover = nullptr;
  for (const auto& [name, cover] : covers) {
    if (best_cover == nullptr || cover.samples > best_cover->samples ||
        (cover.samples == best_cover->samples &&
         cover.distance_sum / cover.samples < best_cover->distance_sum / best_cover->samples)) {
      best = &name;
      best_cover = &cover;
    }
  }
  if (best == nullptr || 2 * best_cover->samples <= static_cast<int>(samples.size())) return {};
  return *best;
}

void LabelEdgeStreets(TopologicalMap& map, const std::vector<TopoStreet>& streets) {
  for (TopoEdge& e : map.edges)
    e.street = StreetAlong(e.polyline_enu, streets, map.options.street_max_distance_m);
}

}  // namespace semslam
