#include "semslam/sim/raycaster.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/semantics/class_table.h"

namespace semslam::sim {
namespace {

constexpr float kEpsilon = 1e-4f;
constexpr float kHuge = 1e30f;

}  // namespace

SceneIndex::SceneIndex(const City& city, float cell_size) : city_(city), cell_(cell_size) {
  Require(cell_size > 0.1f && std::isfinite(cell_size), "SceneIndex: cell size must be > 0.1 m");
  x0_ = static_cast<float>(city.min_corner.x()) - cell_;
  y0_ = static_cast<float>(city.min_corner.y()) - cell_;
  nx_ = std::max(1, static_cast<int>(std::ceil((city.max_corner.x() + cell_ - x0_) / cell_)));
  ny_ = std::max(1, static_cast<int>(std::ceil((city.max_corner.y() + cell_ - y0_) / cell_)));
  top_ = city.max_height + 0.01f;
  const size_t cells = static_cast<size_t>(nx_) * static_cast<size_t>(ny_);
  std::vector<std::uint32_t> count(cells + 1, 0);
  cell_top_.assign(cells, 0.0f);
  auto for_cells = [&](const Primitive& p, auto&& fn) {
    const int cx0 = CellX(p.lo.x()), cx1 = CellX(p.hi.x());
    const int cy0 = CellY(p.lo.y()), cy1 = CellY(p.hi.y());
    for (int cy = cy0; cy <= cy1; ++cy) {
      for (int cx = cx0; cx <= cx1; ++cx)
        fn(static_cast<size_t>(cy) * static_cast<size_t>(nx_) + static_cast<size_t>(cx));
    }
  };
  for (const Primitive& p : city.primitives) for_cells(p, [&](size_t c) { ++count[c + 1]; });
  start_.assign(cells + 1, 0);
  for (size_t c = 0; c < cells; ++c) start_[c + 1] = start_[c] + count[c + 1];
  items_.assign(start_.back(), Item{0, 0, 0});
  std::vector<std::uint32_t> fill(start_.begin(), start_.end() - 1);
  for (size_t i = 0; i < city.primitives.size(); ++i) {
    const Primitive& p = city.primitives[i];
    for_cells(p, [&](size_t c) {
      items_[fill[c]++] = Item{static_cast<std::uint32_t>(i), p.lo.z(), p.hi.z()};
      cell_top_[c] = std::max(cell_top_[c], p.hi.z());
    });
  }
  cnx_ = (nx_ + kCoarse - 1) / kCoarse;
  cny_ = (ny_ + kCoarse - 1) / kCoarse;
  coarse_top_.assign(static_cast<size_t>(cnx_) * static_cast<size_t>(cny_), 0.0f);
  for (int cy = 0; cy < ny_; ++cy) {
    for (int cx = 0; cx < nx_; ++cx) {
      float& top = coarse_top_[static_cast<size_t>(cy / kCoarse) * static_cast<size_t>(cnx_) +
                               static_cast<size_t>(cx / kCoarse)];
      top = std::max(top,
                     cell_top_[static_cast<size_t>(cy) * static_cast<size_t>(nx_) + static_cast<size_t>(cx)]);
    }
  }
}

int SceneIndex::CellX(float x) const {
  return std::clamp(static_cast<int>(std::floor((x - x0_) / cell_)), 0, nx_ - 1);
}
int SceneIndex::CellY(float y) const {
  return std::clamp(static_cast<int>(std::floor((y - y0_) / cell_)), 0, ny_ - 1);
}

bool SceneIndex::IntersectPrimitive(int index, const Eigen::Vector3f& o, const Eigen::Vector3f& d,
                                    const Eigen::Vector3f& inv_d, float* best_t, RayHit* hit) const {
  const Primitive& p = city_.primitives[static_cast<size_t>(index)];
  switch (p.shape) {
    case Shape::kBox: {
      float t_near = -kHuge, t_far = kHuge;
      int axis = 0;
      for (int k = 0; k < 3; ++k) {
        float t1 = (p.lo[k] - o[k]) * inv_d[k];
        float t2 = (p.hi[k] - o[k]) * inv_d[k];
        if (t1 > t2) std::swap(t1, t2);
        if (t1 > t_near) {
          t_near = t1;
          axis = k;
        }
        t_far = std::min(t_far, t2);
      }
      if (t_near > t_far || t_near <= kEpsilon || t_near >= *best_t) return false;
      *best_t = t_near;
      hit->t = t_near;
      hit->primitive = index;
      hit->axis = axis;
      hit->normal = Eigen::Vector3f::Zero();
      hit->normal[axis] = d[axis] > 0 ? -1.0f : 1.0f;
      return true;
    }
    case Shape::kCylinder: {
      const float r = 0.5f * (p.hi.x() - p.lo.x());
      const float cx = 0.5f * (p.lo.x() + p.hi.x()), cy = 0.5f * (p.lo.y() + p.hi.y());
      const float ox = o.x() - cx, oy = o.y() - cy;
      const float a = d.x() * d.x() + d.y() * d.y();
      if (a > 1e-9f) {
        const float b = ox * d.x() + oy * d.y();
        const float c = ox * ox + oy * oy - r * r;
        const float disc = b * b - a * c;
        if (disc < 0) return false;
        const float t = (-b - std::sqrt(disc)) / a;
        if (t > kEpsilon && t < *best_t) {
          const float z = o.z() + t * d.z();
          if (z >= p.lo.z() && z <= p.hi.z()) {
            *best_t = t;
            hit->t = t;
            hit->primitive = index;
            hit->axis = -1;
            hit->normal = Eigen::Vector3f((ox + t * d.x()) / r, (oy + t * d.y()) / r, 0.0f);
            return true;
          }
        }
      }
      if (d.z() < 0) {  // top cap
        const float t = (p.hi.z() - o.z()) / d.z();
        if (t > kEpsilon && t < *best_t) {
          const float px = ox + t * d.x(), py = oy + t * d.y();
          if (px * px + py * py <= r * r) {
            *best_t = t;
            hit->t = t;
            hit->primitive = index;
            hit->axis = 2;
            hit->normal = Eigen::Vector3f::UnitZ();
            return true;
          }
        }
      }
      return false;
    }
    case Shape::kEllipsoid: {
      const Eigen::Vector3f c = 0.5f * (p.lo + p.hi);
      const Eigen::Vector3f inv_r = (0.5f * (p.hi - p.lo)).cwiseInverse();
      const Eigen::Vector3f oo = (o - c).cwiseProduct(inv_r);
      const Eigen::Vector3f dd = d.cwiseProduct(inv_r);
      const float a = dd.squaredNorm();
      const float b = oo.dot(dd);
      const float cc = oo.squaredNorm() - 1.0f;
      const float disc = b * b - a * cc;
      if (disc < 0) return false;
      const float t = (-b - std::sqrt(disc)) / a;
      if (t <= kEpsilon || t >= *best_t) return false;
      *best_t = t;
      hit->t = t;
      hit->primitive = index;
      hit->axis = -1;
      hit->normal = (oo + t * dd).cwiseProduct(inv_r).normalized();
      return true;
    }
  }
  return false;
}

bool SceneIndex::Intersect(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float t_max,
                           RayHit* hit) const {
  float t_end = t_max;
  bool ground = false;
  if (d.z() < 0 && o.z() > 0) {
    const float tg = -o.z() / d.z();
    if (tg <= t_end) {
      t_end = tg;
      ground = true;
    }
  }
  if (d.z() > 0) {
    if (o.z() >= top_) return false;
    t_end = std::min(t_end, (top_ - o.z()) / d.z());
  }
  const Eigen::Vector3f inv_d(d.x() != 0 ? 1.0f / d.x() : kHuge, d.y() != 0 ? 1.0f / d.y() : kHuge,
                              d.z() != 0 ? 1.0f / d.z() : kHuge);
  // Clip to the grid.
  const float gx1 = x0_ + cell_ * static_cast<float>(nx_), gy1 = y0_ + cell_ * static_cast<float>(ny_);
  float ta = 0, tb = t_end;
  {
    float t1 = (x0_ - o.x()) * inv_d.x(), t2 = (gx1 - o.x()) * inv_d.x();
    if (t1 > t2) std::swap(t1, t2);
    ta = std::max(ta, t1);
    tb = std::min(tb, t2);
    t1 = (y0_ - o.y()) * inv_d.y();
    t2 = (gy1 - o.y()) * inv_d.y();
    if (t1 > t2) std::swap(t1, t2);
    ta = std::max(ta, t1);
    tb = std::min(tb, t2);
  }
  float best = t_end;
  bool found = false;
  // Primitives already tested for this ray (large ones span many cells): a small direct-mapped cache.
  std::uint32_t tested[32];
  std::fill(std::begin(tested), std::end(tested), 0xFFFFFFFFu);
  const int step_x = d.x() > 0 ? 1 : -1, step_y = d.y() > 0 ? 1 : -1;
  const float dz = d.z(), oz = o.z();

  // Visits the fine cells of coarse cell (ccx, ccy) between t_in and t_out; true when done.
  auto fine = [&](int ccx, int ccy, float t_in, float t_out_coarse) {
    const int fx0 = ccx * kCoarse, fy0 = ccy * kCoarse;
    const int fx1 = std::min(fx0 + kCoarse, nx_) - 1, fy1 = std::min(fy0 + kCoarse, ny_) - 1;
    const float tm = t_in + 1e-3f;
    int ix = std::clamp(static_cast<int>(std::floor((o.x() + d.x() * tm - x0_) / cell_)), fx0, fx1);
    int iy = std::clamp(static_cast<int>(std::floor((o.y() + d.y() * tm - y0_) / cell_)), fy0, fy1);
    float next_x =
        d.x() != 0 ? (x0_ + cell_ * static_cast<float>(ix + (d.x() > 0 ? 1 : 0)) - o.x()) * inv_d.x() : kHuge;
    float next_y =
        d.y() != 0 ? (y0_ + cell_ * static_cast<float>(iy + (d.y() > 0 ? 1 : 0)) - o.y()) * inv_d.y() : kHuge;
    const float dt_x = std::abs(cell_ * inv_d.x()), dt_y = std::abs(cell_ * inv_d.y());
    float t0 = t_in;
    while (true) {
      const float t1 = std::min({next_x, next_y, t_out_coarse});
      const size_t c = static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix);
      const float za = oz + dz * t0, zb = oz + dz * t1;
      const float z_low = std::min(za, zb), z_high = std::max(za, zb);
      if (z_low <= cell_top_[c]) {
        for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
          const Item& item = items_[k];
          if (item.z_hi < z_low || item.z_lo > z_high) continue;
          std::uint32_t& slot = tested[item.primitive & 31u];
          if (slot == item.primitive) continue;
          slot = item.primitive;
          if (IntersectPrimitive(static_cast<int>(item.primitive), o, d, inv_d, &best, hit)) found = true;
        }
      }
      if (best <= t1) return true;
      if (t1 >= t_out_coarse) return false;
      if (next_x < next_y) {
        ix += step_x;
        t0 = next_x;
        next_x += dt_x;
        if (ix < fx0 || ix > fx1) return false;
      } else {
        iy += step_y;
        t0 = next_y;
        next_y += dt_y;
        if (iy < fy0 || iy > fy1) return false;
      }
    }
  };

  if (ta < tb) {
    const float coarse = cell_ * static_cast<float>(kCoarse);
    const Eigen::Vector3f start = o + d * ta;
    int cx = std::clamp(static_cast<int>(std::floor((start.x() - x0_) / coarse)), 0, cnx_ - 1);
    int cy = std::clamp(static_cast<int>(std::floor((start.y() - y0_) / coarse)), 0, cny_ - 1);
    const float dt_x = std::abs(coarse * inv_d.x()), dt_y = std::abs(coarse * inv_d.y());
    float next_x = d.x() != 0
                       ? (x0_ + coarse * static_cast<float>(cx + (d.x() > 0 ? 1 : 0)) - o.x()) * inv_d.x()
                       : kHuge;
    float next_y = d.y() != 0
                       ? (y0_ + coarse * static_cast<float>(cy + (d.y() > 0 ? 1 : 0)) - o.y()) * inv_d.y()
                       : kHuge;
    float t0 = ta;
    while (true) {
      const float t1 = std::min({next_x, next_y, tb});
      const float z_low = std::min(oz + dz * t0, oz + dz * t1);
      if (z_low <=
          coarse_top_[static_cast<size_t>(cy) * static_cast<size_t>(cnx_) + static_cast<size_t>(cx)]) {
        if (fine(cx, cy, t0, t1)) break;
      }
      if (best <= t1 || t1 >= tb) break;
      if (next_x < next_y) {
        cx += step_x;
        t0 = next_x;
        next_x += dt_x;
        if (cx < 0 || cx >= cnx_) break;
      } else {
        cy += step_y;
        t0 = next_y;
        next_y += dt_y;
        if (cy < 0 || cy >= cny_) break;
      }
    }
  }
  if (found) return true;
  if (ground) {
    hit->t = t_end;
    hit->primitive = -1;
    hit->axis = 2;
    hit->normal = Eigen::Vector3f::UnitZ();
    return true;
  }
  return false;
}

void SceneIndex::CastColumn(const Eigen::Vector3f& o, const Eigen::Vector3f& horizontal, float yn0, float dyn,
                            int rows, float max_distance, ColumnScratch* sc, ColumnHit* hits) const {
  using Entry = ColumnScratch::Entry;
  const float L = std::hypot(horizontal.x(), horizontal.y());
  const Eigen::Vector2f h(horizontal.x() / L, horizontal.y() / L);
  const float oz = o.z();
  const float s_max = max_distance * L;
  const size_t n = static_cast<size_t>(rows);
  sc->slope.resize(n);
  sc->best.resize(n);
  sc->next.resize(n + 1);
  sc->heap.clear();
  if (sc->stamp.size() != city_.primitives.size()) {
    sc->stamp.assign(city_.primitives.size(), 0u);
    sc->column = 0;
  }
  const std::uint32_t column = ++sc->column;
  std::vector<int>& next = sc->next;
  std::vector<float>& best = sc->best;
  std::vector<float>& slope = sc->slope;
  int first_down = rows;  // first row looking below the horizon
  for (int r = 0; r < rows; ++r) {
    const float yn = yn0 + dyn * static_cast<float>(r);
    slope[static_cast<size_t>(r)] = -yn / L;
    next[static_cast<size_t>(r)] = r;
    hits[r] = ColumnHit{};
    best[static_cast<size_t>(r)] = kHuge;
    if (yn > 0 && first_down == rows) first_down = r;
    if (yn > 0) {
      // The ground is the first candidate of every row looking down.
      const float s_ground = oz / (yn / L);
      if (s_ground <= s_max) {
        best[static_cast<size_t>(r)] = s_ground;
        hits[r].lambda = s_ground / L;
        hits[r].primitive = -1;
      }
    }
  }
  next[n] = rows;
  auto find = [&](int r) {
    int root = r;
    while (next[static_cast<size_t>(root)] != root) root = next[static_cast<size_t>(root)];
    while (next[static_cast<size_t>(r)] != root) {
      const int up = next[static_cast<size_t>(r)];
      next[static_cast<size_t>(r)] = root;
      r = up;
    }
    return root;
  };
  // Entries are visited in order of s_in: a row whose nearest hit is nearer than the current `front` is
  // final.
  float front = 0;
  auto is_open = [&](int r) {
    return next[static_cast<size_t>(r)] == r && best[static_cast<size_t>(r)] > front;
  };
  // No row that is not final can hit anything beyond this horizontal distance.
  int up = first_down - 1, down = first_down;
  auto stop_distance = [&]() {
    while (up >= 0 && !is_open(up)) --up;
    while (down < rows && !is_open(down)) ++down;
    float limit = 0;
    if (up >= 0) {
      const float k = slope[static_cast<size_t>(up)];
      limit = k > 1e-9f ? (top_ - oz) / k : s_max;
    }
    if (down < rows) limit = std::max(limit, best[static_cast<size_t>(down)]);
    return std::min(limit, s_max);
  };
  const float row_scale = L / dyn;  // rows per unit of slope
  auto process = [&](const Entry& e) {
    const float s0 = std::max(e.s_in, 1e-4f);
    if (e.s_out <= s0) return;
    const float zl = e.z_lo - oz, zh = e.z_hi - oz;
    const float k_hi = std::max(zh / s0, zh / e.s_out), k_lo = std::min(zl / s0, zl / e.s_out);
    // slope = -(yn0 + dyn r) / L  <=>  r = (-slope L - yn0) / dyn
    const int r0 = std::max(0, static_cast<int>(std::floor(-k_hi * row_scale - yn0 / dyn)) - 1);
    const int r1 = std::min(rows - 1, static_cast<int>(std::ceil(-k_lo * row_scale - yn0 / dyn)) + 1);
    if (r0 > r1) return;
    const Primitive& p = city_.primitives[e.primitive];
    for (int r = find(r0); r <= r1; r = find(r + 1)) {
      if (best[static_cast<size_t>(r)] <= e.s_in) {
        next[static_cast<size_t>(r)] = r + 1;  // final: nothing left starts before its hit
        continue;
      }
      const float k = slope[static_cast<size_t>(r)];
      float s_hit;
      Eigen::Vector3f normal;
      int axis;
      if (p.shape == Shape::kEllipsoid) {
        const Eigen::Vector3f d(horizontal.x(), horizontal.y(), k * L);  // lambda parametrization
        const Eigen::Vector3f c = 0.5f * (p.lo + p.hi);
        const Eigen::Vector3f inv_r = (0.5f * (p.hi - p.lo)).cwiseInverse();
        const Eigen::Vector3f oo = (o - c).cwiseProduct(inv_r);
        const Eigen::Vector3f dd = d.cwiseProduct(inv_r);
        const float a = dd.squaredNorm(), b = oo.dot(dd), cc = oo.squaredNorm() - 1.0f;
        const float disc = b * b - a * cc;
        if (disc < 0) continue;
        const float lambda = (-b - std::sqrt(disc)) / a;
        if (lambda <= 0) continue;
        s_hit = lambda * L;
        normal = (oo + lambda * dd).cwiseProduct(inv_r).normalized();
        axis = -1;
      } else {
        const float z_in = oz + k * s0;
        if (z_in >= e.z_lo && z_in <= e.z_hi) {
          if (e.s_in <= 0) continue;  // the camera is inside
          s_hit = e.s_in;
          if (e.axis >= 0) {
            normal = Eigen::Vector3f::Zero();
            normal[e.axis] = h[e.axis] > 0 ? -1.0f : 1.0f;
            axis = e.axis;
          } else {
            const Eigen::Vector2f centre = 0.5f * (p.lo + p.hi).head<2>();
            const Eigen::Vector2f radial = (o.head<2>() + h * s_hit - centre).normalized();
            normal = Eigen::Vector3f(radial.x(), radial.y(), 0.0f);
            axis = -1;
          }
        } else if (z_in > e.z_hi) {
          if (k >= 0) continue;
          s_hit = (e.z_hi - oz) / k;
          normal = Eigen::Vector3f::UnitZ();
          axis = 2;
        } else {
          if (k <= 0) continue;
          s_hit = (e.z_lo - oz) / k;
          normal = -Eigen::Vector3f::UnitZ();
          axis = 2;
        }
        if (s_hit > e.s_out) continue;
      }
      if (s_hit >= best[static_cast<size_t>(r)] || s_hit > s_max) continue;
      best[static_cast<size_t>(r)] = s_hit;
      ColumnHit& hit = hits[r];
      hit.lambda = s_hit / L;
      hit.primitive = static_cast<int>(e.primitive);
      hit.normal = normal;
      hit.axis = axis;
    }
  };
  auto add = [&](std::uint32_t index) {
    if (sc->stamp[index] == column) return;
    sc->stamp[index] = column;
    const Primitive& p = city_.primitives[index];
    Entry e{0, 0, p.lo.z(), p.hi.z(), index, -1};
    if (p.shape == Shape::kBox) {
      float s_in = -kHuge, s_out = kHuge;
      for (int k = 0; k < 2; ++k) {
        if (std::abs(h[k]) < 1e-12f) {
          if (o[k] < p.lo[k] || o[k] > p.hi[k]) return;
          continue;
        }
        float t1 = (p.lo[k] - o[k]) / h[k], t2 = (p.hi[k] - o[k]) / h[k];
        if (t1 > t2) std::swap(t1, t2);
        if (t1 > s_in) {
          s_in = t1;
          e.axis = k;
        }
        s_out = std::min(s_out, t2);
      }
      if (s_in > s_out || s_out <= 0) return;
      e.s_in = s_in;
      e.s_out = s_out;
    } else {
      const Eigen::Vector2f c = 0.5f * (p.lo + p.hi).head<2>();
      const Eigen::Vector2f r = 0.5f * (p.hi - p.lo).head<2>();
      const Eigen::Vector2f oo = (o.head<2>() - c).cwiseQuotient(r);
      const Eigen::Vector2f hh = h.cwiseQuotient(r);
      const float a = hh.squaredNorm(), b = oo.dot(hh), cc = oo.squaredNorm() - 1.0f;
      const float disc = b * b - a * cc;
      if (disc < 0) return;
      const float root = std::sqrt(disc);
      e.s_in = (-b - root) / a;
      e.s_out = (-b + root) / a;
      if (e.s_out <= 0) return;
    }
    sc->heap.push_back(e);
    std::push_heap(sc->heap.begin(), sc->heap.end(), std::greater<Entry>());
  };
  auto drain = [&](float limit) {
    // Processes the entries that start before `limit`, nearest first.
    while (!sc->heap.empty() && sc->heap.front().s_in <= limit) {
      std::pop_heap(sc->heap.begin(), sc->heap.end(), std::greater<Entry>());
      const Entry e = sc->heap.back();
      sc->heap.pop_back();
      front = e.s_in;
      process(e);
    }
  };

  // 2D DDA along the column's line, clipped to the grid.
  const float gx1 = x0_ + cell_ * static_cast<float>(nx_), gy1 = y0_ + cell_ * static_cast<float>(ny_);
  const float inv_x = h.x() != 0 ? 1.0f / h.x() : kHuge, inv_y = h.y() != 0 ? 1.0f / h.y() : kHuge;
  float ta = 0, tb = s_max;
  {
    float t1 = (x0_ - o.x()) * inv_x, t2 = (gx1 - o.x()) * inv_x;
    if (t1 > t2) std::swap(t1, t2);
    ta = std::max(ta, t1);
    tb = std::min(tb, t2);
    t1 = (y0_ - o.y()) * inv_y;
    t2 = (gy1 - o.y()) * inv_y;
    if (t1 > t2) std::swap(t1, t2);
    ta = std::max(ta, t1);
    tb = std::min(tb, t2);
  }
  if (ta < tb) {
    int ix = CellX(o.x() + h.x() * (ta + 1e-3f)), iy = CellY(o.y() + h.y() * (ta + 1e-3f));
    const int step_x = h.x() > 0 ? 1 : -1, step_y = h.y() > 0 ? 1 : -1;
    const float dt_x = std::abs(cell_ * inv_x), dt_y = std::abs(cell_ * inv_y);
    float next_x =
        h.x() != 0 ? (x0_ + cell_ * static_cast<float>(ix + (h.x() > 0 ? 1 : 0)) - o.x()) * inv_x : kHuge;
    float next_y =
        h.y() != 0 ? (y0_ + cell_ * static_cast<float>(iy + (h.y() > 0 ? 1 : 0)) - o.y()) * inv_y : kHuge;
    float t_in = ta;
    stop_distance();  // places the horizon pointers
    while (true) {
      const float t_out = std::min({next_x, next_y, tb});
      const size_t c = static_cast<size_t>(iy) * static_cast<size_t>(nx_) + static_cast<size_t>(ix);
      // The cell matters while a row looking down is open, or the lowest open row looking up passes below the
      // top of the cell.
      const bool needed =
          down < rows || (up >= 0 && oz + slope[static_cast<size_t>(up)] * t_in <= cell_top_[c]);
      if (needed) {
        for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) add(items_[k].primitive);
      }
      drain(t_out);
      front = sc->heap.empty() ? t_out : std::min(t_out, sc->heap.front().s_in);
      if (t_out >= stop_distance() || t_out >= tb) break;
      t_in = t_out;
      if (next_x < next_y) {
        ix += step_x;
        next_x += dt_x;
        if (ix < 0 || ix >= nx_) break;
      } else {
        iy += step_y;
        next_y += dt_y;
        if (iy < 0 || iy >= ny_) break;
      }
    }
  }
  drain(std::min(stop_distance(), s_max));
}

float SurfaceDistance(const Primitive& p, const Eigen::Vector3f& x) {
  switch (p.shape) {
    case Shape::kBox: {
      const Eigen::Vector3f q = (p.lo - x).cwiseMax(x - p.hi);
      const float outside = q.cwiseMax(0.0f).norm();
      const float inside = std::min(q.maxCoeff(), 0.0f);
      return std::abs(outside + inside);
    }
    case Shape::kCylinder: {
      const float r = 0.5f * (p.hi.x() - p.lo.x());
      const float cx = 0.5f * (p.lo.x() + p.hi.x()), cy = 0.5f * (p.lo.y() + p.hi.y());
      const float radial = std::hypot(x.x() - cx, x.y() - cy) - r;
      const float vertical = std::max(p.lo.z() - x.z(), x.z() - p.hi.z());
      const float outside = std::hypot(std::max(radial, 0.0f), std::max(vertical, 0.0f));
      const float inside = std::min(std::max(radial, vertical), 0.0f);
      return std::abs(outside + inside);
    }
    case Shape::kEllipsoid: {
      const Eigen::Vector3f c = 0.5f * (p.lo + p.hi);
      const Eigen::Vector3f r = 0.5f * (p.hi - p.lo);
      const Eigen::Vector3f q = x - c;
      const float k0 = q.cwiseQuotient(r).norm();
      const float k1 = q.cwiseQuotient(r.cwiseProduct(r)).norm();
      if (k1 < 1e-9f) return r.minCoeff();
      return std::abs(k0 * (k0 - 1.0f) / k1);
    }
  }
  return std::numeric_limits<float>::max();
}

NearestSurface SceneIndex::Nearest(const Eigen::Vector3f& x, float radius) const {
  NearestSurface best;
  best.primitive = -1;
  best.distance = std::abs(x.z());
  best.label = static_cast<std::uint8_t>(SemanticClass::kRoad);
  const int cx0 = CellX(x.x() - radius), cx1 = CellX(x.x() + radius);
  const int cy0 = CellY(x.y() - radius), cy1 = CellY(x.y() + radius);
  for (int cy = cy0; cy <= cy1; ++cy) {
    for (int cx = cx0; cx <= cx1; ++cx) {
      const size_t c = static_cast<size_t>(cy) * static_cast<size_t>(nx_) + static_cast<size_t>(cx);
      for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
        const Primitive& p = city_.primitives[items_[k].primitive];
        const float dist = SurfaceDistance(p, x);
        if (dist < best.distance) {
          best.distance = dist;
          best.primitive = static_cast<int>(items_[k].primitive);
          best.label = p.label;
        }
      }
    }
  }
  return best;
}

}  // namespace semslam::sim
