#include "semslam/sim/route.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "semslam/core/error.h"
#include "semslam/sim/random.h"
#include "semslam/sim/route_tour.h"

namespace semslam::sim {
namespace {

constexpr int kDi[4] = {1, 0, -1, 0};  // headings: east, north, west, south
constexpr int kDj[4] = {0, 1, 0, -1};
constexpr double kStep = 0.25;  // spacing of the dense path, metres
constexpr double kLeftRadius = 11.0;
constexpr double kRightRadius = 7.5;
constexpr double kSmoothSigma = 2.0;  // metres
// What cars do on the KITTI drives, at 10 Hz (heading of the camera's forward axis between frames; lateral
// acceleration = speed x yaw rate). Ground-truth poses of odometry sequences 00-10: yaw rate at most 47.8 deg/s
// (4.8 deg per frame, sequence 00; 99.9th percentile 4.2 deg per frame over all sequences), lateral
// acceleration at most 5.5 m/s^2 (sequence 01, on the highway; 99.9th percentile 4.9). Sequence 07: 34.6 deg/s,
// 3.3 m/s^2. OXTS of raw drive 0005 (slow urban): 14.4 deg/s, 1.3 m/s^2 (1.6 deg per frame); drive 0001:
// 2.4 deg/s, 0.5 m/s^2. The limits (kRouteMaxYawRate, kRouteMaxLateralAcceleration in route.h) sit above
// sequence 07's and drive 0005's maxima, so the route has turns as sharp as theirs, and below the sharpest of
// all the sequences. Corners are driven as arcs at the speed both limits allow: a right turn (7.5 m) at
// 5.2 m/s, a left turn (11 m) at 6.6 m/s.
constexpr double kAcceleration = 1.0;
constexpr double kDeceleration = 1.5;

struct Move {
  bool turn = false;
  int value = 0;  // blocks to go, or +1 (left) / -1 (right)
};

class IntersectionPlanner {
 public:
  IntersectionPlanner(const StreetGrid& grid, Rng& rng) : g_(grid), rng_(rng) {}

  std::vector<int> Plan(double needed_length) {
    // Start near the middle of the drivable grid, facing a random direction, one block before the first loop.
    const int ni = g_.ni(), nj = g_.nj();
    i_ = std::clamp(ni / 2 + rng_.UniformInt(-1, 1), 1, ni - 2);
    j_ = std::clamp(nj / 2 + rng_.UniformInt(-1, 1), 1, nj - 2);
    heading_ = rng_.UniformInt(0, 3);
    arrival_ = heading_;
    const int pi = i_ - kDi[heading_], pj = j_ - kDj[heading_];
    if (g_.Drivable(pi, pj)) seq_.push_back(g_.IntersectionId(pi, pj));
    seq_.push_back(g_.IntersectionId(i_, j_));
    Extend(needed_length, /*first=*/true);
    return seq_;
  }

  // Goes on from the end of a planned drive (two intersections or more), with the loops of Plan(), through
  // none of the `avoid` intersections (unless the town leaves no other way).
  std::vector<int> Continue(std::vector<int> seq, double needed_length, std::vector<int> avoid) {
    avoid_ = std::move(avoid);
    Require(seq.size() >= 2, "PlanRoute: a drive to continue needs two intersections");
    seq_ = std::move(seq);
    const int last = seq_.back(), before = seq_[seq_.size() - 2];
    i_ = g_.I(last);
    j_ = g_.J(last);
    heading_ = -1;
    for (int h = 0; h < 4; ++h) {
      if (g_.I(before) + kDi[h] == i_ && g_.J(before) + kDj[h] == j_) heading_ = h;
    }
    Require(heading_ >= 0,
            "PlanRoute: the drive to continue does not end between neighbouring intersections");
    arrival_ = heading_;
    Extend(needed_length, /*first=*/false);
    return seq_;
  }

 private:
  // Adds loops until the drive is `needed_length` long; the first loop of a drive is a small one.
  void Extend(double needed_length, bool first) {
    int sense = rng_.Bernoulli(0.5) ? 1 : -1;
    while (Length() < needed_length) {
      bool placed = false;
      for (int attempt = 0; attempt < 60 && !placed; ++attempt) {
        const int s = attempt < 30 ? sense : -sense;
        const int a = rng_.UniformInt(1, 2), b = rng_.UniformInt(1, 2), c = rng_.UniformInt(0, 2);
        if (first && a + b > 3) continue;
        const std::vector<Move> moves = {{false, a}, {true, s},  {false, b}, {true, s},  {false, a},
                                         {true, s},  {false, b}, {true, s},  {false, a}, {true, s},
                                         {false, 1}, {false, c}, {true, -s}};
        if (Apply(moves)) {
          placed = true;
          sense = -s;
        }
      }
      if (!placed) Fallback();
      first = false;
    }
  }

  double Length() const {
    double total = 0;
    for (size_t k = 1; k < seq_.size(); ++k)
      total += (g_.Position(seq_[k]) - g_.Position(seq_[k - 1])).norm();
    return total;
  }

  // Applies the moves if every intersection they reach is drivable.
  bool Apply(const std::vector<Move>& moves) {
    int i = i_, j = j_, h = heading_, last_driven = arrival_;
    std::vector<int> added;
    for (const Move& m : moves) {
      if (m.turn) {
        h = (h + (m.value > 0 ? 1 : 3)) % 4;
        continue;
      }
      if (m.value > 0) last_driven = h;
      for (int k = 0; k < m.value; ++k) {
        i += kDi[h];
        j += kDj[h];
        if (!g_.Drivable(i, j)) return false;
        const int id = g_.IntersectionId(i, j);
        // A loop comes back to where it starts: that one may be avoided.
        if (id != g_.IntersectionId(i_, j_) && std::find(avoid_.begin(), avoid_.end(), id) != avoid_.end())
          return false;
        added.push_back(id);
      }
    }
    // The last move is a turn that the next module's first block completes: it must lead somewhere.
    if (!g_.Drivable(i + kDi[h], j + kDj[h])) return false;
    seq_.insert(seq_.end(), added.begin(), added.end());
    i_ = i;
    j_ = j;
    heading_ = h;
    arrival_ = last_driven;
    return true;
  }

  // One block towards the middle of the town, never back the way the car came: heading_ may hold a turn the
  // car has not driven yet (a module ends with one), so a turn from it could be a U-turn from where the car
  // arrived (at seeds 3, 77 and 4242 it was: a reversal on a 3.6 m circle, 25 deg per frame).
  void Fallback() {
    const double ci = 0.5 * (g_.ni() - 1), cj = 0.5 * (g_.nj() - 1);
    int best = -1;
    double best_d = 1e18;
    for (int turn : {0, 1, 3}) {
      const int h = (heading_ + turn) % 4;
      if (h == (arrival_ + 2) % 4) continue;
      const int i = i_ + kDi[h], j = j_ + kDj[h];
      if (!g_.Drivable(i, j)) continue;
      const double d = std::hypot(i - ci, j - cj) + (turn == 0 ? 0.5 : 0.0);
      if (d < best_d) {
        best_d = d;
        best = h;
      }
    }
    Require(best >= 0, "PlanRoute: the town is too small to drive in");
    heading_ = best;
    arrival_ = best;
    i_ += kDi[best];
    j_ += kDj[best];
    seq_.push_back(g_.IntersectionId(i_, j_));
  }

  const StreetGrid& g_;
  Rng& rng_;
  std::vector<int> seq_;
  std::vector<int> avoid_;
  int i_ = 0, j_ = 0, heading_ = 0;
  int arrival_ = 0;  // the heading of the last block driven
};

Eigen::Vector2d Right(const Eigen::Vector2d& e) { return {e.y(), -e.x()}; }
double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

struct DensePath {
  std::vector<Eigen::Vector2d> points;
  std::vector<int> piece;  // index k of the intersection sequence segment (seq[k] -> seq[k+1])
  struct Corner {
    double s = 0;  // arc length of the apex
    bool left = false;
    int intersection = 0;
  };
  std::vector<Corner> corners;
};

DensePath BuildPath(const StreetGrid& g, const std::vector<int>& seq, double start_fraction) {
  DensePath path;
  const size_t n = seq.size() - 1;  // segments
  std::vector<Eigen::Vector2d> p(seq.size()), e(n);
  for (size_t k = 0; k < seq.size(); ++k) p[k] = g.Position(seq[k]);
  for (size_t k = 0; k < n; ++k) e[k] = (p[k + 1] - p[k]).normalized();
  const double lo = g.lane_offset;
  auto add_line = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, int piece) {
    const double len = (b - a).norm();
    const int steps = std::max(1, static_cast<int>(std::round(len / kStep)));
    for (int s = 0; s < steps; ++s) {
      path.points.push_back(a + (b - a) * (static_cast<double>(s) / steps));
      path.piece.push_back(piece);
    }
  };
  struct Arc {
    bool turn = false;
    bool left = false;
    Eigen::Vector2d t1, t2, centre;
    double radius = 0;
  };
  std::vector<Arc> arcs(seq.size());
  for (size_t k = 1; k < n; ++k) {
    const double c = Cross(e[k - 1], e[k]);
    if (std::abs(c) < 0.5) continue;
    Arc& a = arcs[k];
    a.turn = true;
    a.left = c > 0;
    a.radius = a.left ? kLeftRadius : kRightRadius;
    const Eigen::Vector2d q = p[k] + Right(e[k - 1]) * lo + Right(e[k]) * lo;
    a.t1 = q - e[k - 1] * a.radius;
    a.t2 = q + e[k] * a.radius;
    a.centre = a.t1 + (a.left ? -Right(e[k - 1]) : Right(e[k - 1])) * a.radius;
  }
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d a = k == 0
                                  ? Eigen::Vector2d(p[0] + (p[1] - p[0]) * start_fraction + Right(e[0]) * lo)
                              : arcs[k].turn ? arcs[k].t2
                                             : Eigen::Vector2d(p[k] + Right(e[k]) * lo);
    const Eigen::Vector2d b =
        k + 1 < n && arcs[k + 1].turn ? arcs[k + 1].t1 : Eigen::Vector2d(p[k + 1] + Right(e[k]) * lo);
    add_line(a, b, static_cast<int>(k));
    if (k + 1 < n && arcs[k + 1].turn) {
      const Arc& arc = arcs[k + 1];
      const double sweep = (arc.left ? 1.0 : -1.0) * M_PI / 2;
      const Eigen::Vector2d r0 = arc.t1 - arc.centre;
      const double theta0 = std::atan2(r0.y(), r0.x());
      const int steps = static_cast<int>(std::round(std::abs(sweep) * arc.radius / kStep));
      for (int s = 0; s < steps; ++s) {
        const double th = theta0 + sweep * s / steps;
        if (s == steps / 2) {
          path.corners.push_back({static_cast<double>(path.points.size()) * kStep, arc.left, seq[k + 1]});
        }
        path.points.push_back(arc.centre + arc.radius * Eigen::Vector2d(std::cos(th), std::sin(th)));
        path.piece.push_back(static_cast<int>(s < steps / 2 ? k : k + 1));
      }
    }
  }
  path.points.push_back(p[n] + Right(e[n - 1]) * lo);
  path.piece.push_back(static_cast<int>(n - 1));
  // Smooth to continuous curvature (a Gaussian over arc length; the ends stay where they are).
  const int radius = static_cast<int>(std::ceil(3 * kSmoothSigma / kStep));
  std::vector<double> kernel(static_cast<size_t>(radius + 1));
  for (int r = 0; r <= radius; ++r)
    kernel[static_cast<size_t>(r)] = std::exp(-0.5 * std::pow(r * kStep / kSmoothSigma, 2));
  std::vector<Eigen::Vector2d> smooth(path.points.size());
  const int count = static_cast<int>(path.points.size());
  for (int i = 0; i < count; ++i) {
    const int r_max = std::min({radius, i, count - 1 - i});
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    double w = 0;
    for (int r = -r_max; r <= r_max; ++r) {
      const double k = kernel[static_cast<size_t>(std::abs(r))];
      sum += k * path.points[static_cast<size_t>(i + r)];
      w += k;
    }
    smooth[static_cast<size_t>(i)] = sum / w;
  }
  path.points = std::move(smooth);
  return path;
}

double WrapAngle(double a) {
  while (a > M_PI) a -= 2 * M_PI;
  while (a < -M_PI) a += 2 * M_PI;
  return a;
}

}  // namespace

void RouteOptions::Check() const {
  Require(frames >= 1 && frames <= 1000000, "RouteOptions.frames must be in [1, 1000000]");
  Require(std::isfinite(rate_hz) && rate_hz > 0 && rate_hz <= 1000,
          "RouteOptions.rate_hz must be in (0, 1000]");
  Require(std::isfinite(min_speed) && min_speed > 0, "RouteOptions.min_speed must be > 0");
  Require(std::isfinite(max_speed) && max_speed >= min_speed && max_speed <= 40,
          "RouteOptions.max_speed must be in [min_speed, 40] m/s");
  Require(std::isfinite(camera_height) && camera_height > 0.2 && camera_height < 5,
          "RouteOptions.camera_height must be in (0.2, 5) m");
}

Route PlanRoute(const City& city, const RouteOptions& options) {
  options.Check();
  const StreetGrid& g = city.grid;
  Require(g.ni() >= 4 && g.nj() >= 4, "PlanRoute: the town needs at least 3 x 3 blocks");
  const std::uint64_t base_seed = options.seed != 0 ? options.seed : city.options.seed;
  const double duration = (options.frames - 1) / options.rate_hz;
  const double needed = duration * options.max_speed + 250.0;
  std::vector<int> seq;
  if (options.route_seed == 0) {
    Rng rng = Rng::Stream(base_seed, 11);
    seq = IntersectionPlanner(g, rng).Plan(needed);
  } else {
    Rng rng = Rng::Stream(base_seed, Hash3(13, options.route_seed, 0));
    std::vector<int> hub_tour = PlanHubTour(g, city.options.seed, options.route_seed, rng);
    // Away from the hub: what follows is the drive's own.
    const TownHub hub = FindTownHub(g, city.options.seed);
    seq = IntersectionPlanner(g, rng).Continue(std::move(hub_tour), needed,
                                               std::vector<int>(hub.corners.begin(), hub.corners.end()));
  }
  if (options.reverse) std::reverse(seq.begin(), seq.end());
  const double start_fraction = 0.5;
  const DensePath path = BuildPath(g, seq, start_fraction);
  const size_t count = path.points.size();

  // Headings and curvature of the dense path.
  std::vector<double> heading(count), curvature(count, 0.0);
  for (size_t i = 0; i < count; ++i) {
    const size_t a = i == 0 ? 0 : i - 1, b = i + 1 < count ? i + 1 : count - 1;
    const Eigen::Vector2d d = path.points[b] - path.points[a];
    heading[i] = std::atan2(d.y(), d.x());
  }
  for (size_t i = 1; i + 1 < count; ++i) {
    curvature[i] = WrapAngle(heading[i + 1] - heading[i - 1]) / (2 * kStep);
  }
  // Speed profile: a cruise speed per street, the lateral acceleration limit in turns, limited acceleration.
  std::vector<double> cruise(seq.size());
  const double cruise_lo = std::min(std::max(options.min_speed, 10.0), options.max_speed);
  // One stream per street of the drive: a longer drive starts exactly as a shorter one.
  const std::uint64_t speed_seed =
      options.route_seed == 0 ? base_seed : HashCombine(base_seed, Hash3(13, options.route_seed, 1));
  for (size_t k = 0; k < cruise.size(); ++k) {
    Rng street = Rng::Stream(speed_seed, Hash3(12, k, options.reverse ? 1 : 0));
    cruise[k] = street.Uniform(cruise_lo, options.max_speed);
  }
  // In turns the car slows below the cruise speed as far as the yaw-rate and lateral-acceleration limits ask
  // (min_speed bounds the cruise speeds, not the turns: the old floor of 8 m/s gave 61 deg/s and 8.5 m/s^2).
  std::vector<double> v(count);
  for (size_t i = 0; i < count; ++i) {
    const double k = std::abs(curvature[i]);
    const double limit =
        k > 1e-6 ? std::min(std::sqrt(kRouteMaxLateralAcceleration / k), kRouteMaxYawRate / k) : 1e9;
    v[i] = std::min(limit, cruise[static_cast<size_t>(path.piece[i])]);
  }
  for (size_t i = 1; i < count; ++i)
    v[i] = std::min(v[i], std::sqrt(v[i - 1] * v[i - 1] + 2 * kAcceleration * kStep));
  for (size_t i = count - 1; i-- > 0;)
    v[i] = std::min(v[i], std::sqrt(v[i + 1] * v[i + 1] + 2 * kDeceleration * kStep));

  const double total = static_cast<double>(count - 1) * kStep;
  auto speed_at = [&](double s) {
    const double x = std::clamp(s / kStep, 0.0, static_cast<double>(count - 1));
    const size_t i = std::min(static_cast<size_t>(x), count - 2);
    const double f = x - static_cast<double>(i);
    return v[i] * (1 - f) + v[i + 1] * f;
  };
  const double dt = 1.0 / options.rate_hz;
  std::vector<double> s_frames(static_cast<size_t>(options.frames));
  double s = 0;
  for (int f = 0; f < options.frames; ++f) {
    s_frames[static_cast<size_t>(f)] = s;
    // Midpoint integration of ds/dt = v(s), in a few sub-steps.
    for (int sub = 0; sub < 4; ++sub) {
      const double h = dt / 4;
      s += h * speed_at(s + 0.5 * h * speed_at(s));
    }
  }
  if (s_frames.back() > total)
    throw InvalidArgument("PlanRoute: the planned path is too short for the frames");

  Route route;
  route.intersections = seq;
  std::vector<int> piece_segment(seq.size(), -1);
  for (size_t k = 0; k + 1 < seq.size(); ++k) piece_segment[k] = g.SegmentBetween(seq[k], seq[k + 1]);
  for (int f = 0; f < options.frames; ++f) {
    const double sf = s_frames[static_cast<size_t>(f)];
    const double x = std::clamp(sf / kStep, 0.0, static_cast<double>(count - 1));
    const size_t i = std::min(static_cast<size_t>(x), count - 2);
    const double t = x - static_cast<double>(i);
    const Eigen::Vector2d pos = path.points[i] * (1 - t) + path.points[i + 1] * t;
    const double yaw = heading[i] + WrapAngle(heading[i + 1] - heading[i]) * t;
    // Camera: z forward along the heading, x to the right, y down.
    const Eigen::Vector3d forward(std::cos(yaw), std::sin(yaw), 0.0);
    const Eigen::Vector3d right(std::sin(yaw), -std::cos(yaw), 0.0);
    const Eigen::Vector3d down(0, 0, -1);
    Eigen::Matrix3d r;
    r.col(0) = right;
    r.col(1) = down;
    r.col(2) = forward;
    route.town_from_camera.emplace_back(r, Eigen::Vector3d(pos.x(), pos.y(), options.camera_height));
    route.speed.push_back(speed_at(sf));
    route.yaw.push_back(WrapAngle(yaw));
    route.frame_segment.push_back(piece_segment[static_cast<size_t>(path.piece[t < 0.5 ? i : i + 1])]);
  }
  const size_t frames = static_cast<size_t>(options.frames);
  route.yaw_rate.assign(frames, 0.0);
  route.acceleration.assign(frames, 0.0);
  for (size_t f = 0; f < frames; ++f) {
    const size_t a = f == 0 ? 0 : f - 1, b = f + 1 < frames ? f + 1 : frames - 1;
    if (b == a) continue;
    const double span = static_cast<double>(b - a) * dt;
    route.yaw_rate[f] = WrapAngle(route.yaw[b] - route.yaw[a]) / span;
    route.acceleration[f] = (route.speed[b] - route.speed[a]) / span;
  }
  route.length = s_frames.back();
  for (const DensePath::Corner& c : path.corners) {
    if (c.s > s_frames.back() + 1e-9) break;
    const auto it = std::lower_bound(s_frames.begin(), s_frames.end(), c.s);
    size_t f = static_cast<size_t>(it - s_frames.begin());
    if (f > 0 && (f == frames || c.s - s_frames[f - 1] < s_frames[f] - c.s)) --f;
    route.turns.push_back({static_cast<int>(f), c.left, c.intersection});
  }
  return route;
}

}  // namespace semslam::sim
