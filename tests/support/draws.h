#pragma once
// Random vectors for the tests, drawn in one order with every compiler. The arguments of one call are
// evaluated in the order the compiler chooses (GCC: last to first, clang: first to last), so
// `Eigen::Vector3d(d(rng), d(rng), d(rng))` holds other numbers in a clang build than in GCC's. These draw
// the last coordinate first, as GCC did for the draws the tests' bounds were measured with.

#include <Eigen/Core>

namespace semslam::testing {

template <class DistX, class DistY, class Rng>
Eigen::Vector2d DrawVector2(DistX& dx, DistY& dy, Rng& rng) {
  const double y = dy(rng);
  const double x = dx(rng);
  return {x, y};
}

template <class Dist, class Rng>
Eigen::Vector2d DrawVector2(Dist& d, Rng& rng) {
  return DrawVector2(d, d, rng);
}

template <class DistX, class DistY, class DistZ, class Rng>
Eigen::Vector3d DrawVector3(DistX& dx, DistY& dy, DistZ& dz, Rng& rng) {
  const double z = dz(rng);
  const double y = dy(rng);
  const double x = dx(rng);
  return {x, y, z};
}

template <class Dist, class Rng>
Eigen::Vector3d DrawVector3(Dist& d, Rng& rng) {
  return DrawVector3(d, d, d, rng);
}

}  // namespace semslam::testing
