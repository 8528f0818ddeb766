#pragma once
// Ray casting against the town: the analytic ground plane z = 0 (the road) plus the primitives, found through
// a 2D uniform grid over the town traversed with a DDA (Amanatides & Woo 1987). A ray is bounded by its
// ground hit and by the height of the tallest primitive, and cells whose contents lie entirely below the ray
// are skipped. Also answers "which surface is nearest to this point" for ground-truth label lookups.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "semslam/sim/city.h"

namespace semslam::sim {

struct RayHit {
  float t = 0;         // distance along the (unit) direction
  int primitive = -1;  // index into City::primitives; -1: the ground plane
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
  int axis = 2;  // for box faces: the axis of the normal (0, 1, 2); -1 for curved surfaces
};

struct NearestSurface {
  int primitive = -1;  // -1: the ground plane (road)
  float distance = 0;  // metres from the point to that surface
  std::uint8_t label = 0;
};

// One image column of a level camera (its y axis pointing straight down): every ray of the column lies in
// the vertical plane through the camera centre along `horizontal`. Ray of row r:
// origin + lambda * (horizontal + (-yn[r]) * up), lambda = camera z (depth) of the point.
struct ColumnHit {
  float lambda = 0;    // camera z of the hit
  int primitive = -2;  // -1: ground plane, -2: nothing (sky)
  Eigen::Vector3f normal = Eigen::Vector3f::UnitZ();
  int axis = 2;
};

// Scratch memory for CastColumn, one per thread.
struct ColumnScratch {
  struct Entry {
    float s_in, s_out;  // horizontal distances where the column plane enters / leaves the footprint
    float z_lo, z_hi;
    std::uint32_t primitive;
    int axis;  // box: footprint axis that gave s_in; cylinder: -1
    bool operator>(const Entry& o) const { return s_in != o.s_in ? s_in > o.s_in : primitive > o.primitive; }
  };
  std::vector<Entry> heap;
  std::vector<std::uint32_t> stamp;  // per primitive: the column that saw it last
  std::uint32_t column = 0;
  std::vector<int> next;     // next row that is not final (path-compressed)
  std::vector<float> slope;  // per row: height gained per horizontal metre
  std::vector<float> best;   // per row: horizontal distance of the nearest hit so far
};

class SceneIndex {
 public:
  // `city` must outlive the index.
  explicit SceneIndex(const City& city, float cell_size = 4.0f);

  // Nearest surface along origin + t * dir, 0 < t <= t_max (dir unit length). False when the ray leaves the
  // town upwards or passes t_max without a hit (sky).
  bool Intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t_max, RayHit* hit) const;

  // Casts all rays of one column of a level camera at once (see ColumnHit): the column's vertical plane is
  // traversed once, and the primitives it meets are visited front to back, each resolving the rows whose rays
  // hit it. `yn` (rows values, increasing) are the rows' normalized image y; rays end at `max_distance`
  // (camera z). Gives the same hits as Intersect() up to floating-point ties.
  // Row r has yn = yn0 + r * dyn (dyn > 0).
  void CastColumn(const Eigen::Vector3f& origin, const Eigen::Vector3f& horizontal, float yn0, float dyn,
                  int rows, float max_distance, ColumnScratch* scratch, ColumnHit* hits) const;

  // The surface (ground plane or primitive) nearest to `point`, among primitives whose bounds are within
  // `search_radius` of it; the ground plane always counts.
  NearestSurface Nearest(const Eigen::Vector3f& point, float search_radius = 3.0f) const;

  const City& city() const { return city_; }
  // Number of primitive references stored in the grid (for statistics).
  size_t num_references() const { return items_.size(); }

 private:
  bool IntersectPrimitive(int index, const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                          const Eigen::Vector3f& inv_d, float* best_t, RayHit* hit) const;
  int CellX(float x) const;
  int CellY(float y) const;

  // A primitive listed in a cell, with its vertical extent for a quick rejection.
  struct Item {
    std::uint32_t primitive;
    float z_lo, z_hi;
  };

  const City& city_;
  float cell_ = 4.0f;
  float x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  float top_ = 0;
  std::vector<std::uint32_t> start_;  // CSR: cell c holds items_[start_[c] .. start_[c + 1])
  std::vector<Item> items_;
  std::vector<float> cell_top_;  // highest primitive top in the cell
  // Coarse level: kCoarse x kCoarse cells each, with their highest top, to skip empty air quickly.
  static constexpr int kCoarse = 8;
  int cnx_ = 0, cny_ = 0;
  std::vector<float> coarse_top_;
};

// Distance from a point to the surface of one primitive (exact for boxes and cylinders, a close bound for
// ellipsoids).
float SurfaceDistance(const Primitive& primitive, const Eigen::Vector3f& point);

}  // namespace semslam::sim
