#pragma once
// A driven route in ENU for GPS tests: a block loop with turns and a gentle grade, one position per frame.

#include <cmath>
#include <random>
#include <vector>

#include "semslam/geometry/eigen_types.h"

namespace semslam::testing {

// Corners of the route (ENU metres), driven in order at `step_m` per frame; altitude varies by a few metres.
inline Points3d DriveThrough(const std::vector<Eigen::Vector2d>& corners, double step_m) {
  Points3d points;
  double s = 0.0;
  for (size_t i = 0; i + 1 < corners.size(); ++i) {
    const Eigen::Vector2d a = corners[i], b = corners[i + 1];
    const double length = (b - a).norm();
    for (double t = points.empty() ? 0.0 : step_m - std::fmod(s, step_m); t < length; t += step_m) {
      const Eigen::Vector2d p = a + (b - a) * (t / length);
      const double total = s + t;
      points.emplace_back(p.x(), p.y(), 3.0 * std::sin(total / 150.0));
    }
    s += length;
  }
  return points;
}

inline Points3d BlockLoop() {
  return DriveThrough({{0, 0}, {400, 0}, {400, 300}, {0, 300}, {0, 0}, {200, 0}, {200, 150}}, 1.0);
}

inline Eigen::Vector3d Noise3(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(rng), n(rng), n(rng)};
}

}  // namespace semslam::testing
