#pragma once
// Synthetic scenes for the optimizer tests (with the KITTI camera of support/): points in front of it, noise from
// fixed seeds.

#include <random>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/geometry/sim3.h"
#include "support/kitti_camera.h"

namespace semslam::testing_optim {

inline Eigen::Vector3d RandomVector(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(rng), n(rng), n(rng)};
}

// A point in front of a camera, projecting inside its image: camera frame, depth in [min_depth, max_depth].
inline Eigen::Vector3d RandomCameraPoint(std::mt19937& rng, const PinholeCamera& c, double min_depth,
                                         double max_depth) {
  std::uniform_real_distribution<double> u(5.0, c.width - 6.0), v(5.0, c.height - 6.0),
      z(min_depth, max_depth);
  // One statement a draw, in the order GCC evaluated the arguments of UnprojectDepth (support/draws.h).
  const double depth = z(rng);
  const Eigen::Vector2d pixel{u(rng), v(rng)};
  return c.UnprojectDepth(pixel, depth);
}

// A random rigid motion: rotation vector and translation of independent normal coordinates with standard
// deviations `rotation_sigma` (rad) and `translation_sigma` (m). The translation is drawn first (GCC's order
// for the two arguments of Rigid3d, which the tests' bounds were measured with; support/draws.h).
inline Rigid3d RandomRigid(std::mt19937& rng, double rotation_sigma, double translation_sigma) {
  const Eigen::Vector3d translation = RandomVector(rng, translation_sigma);
  return Rigid3d(QuaternionExp(RandomVector(rng, rotation_sigma)), translation);
}

// Small random rigid motion: rotation of about `angle` rad, translation of about `distance` m.
inline Rigid3d Perturbation(std::mt19937& rng, double angle, double distance) {
  return RandomRigid(rng, angle / std::sqrt(3.0), distance / std::sqrt(3.0));
}

inline double RotationError(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return QuaternionLog(a.conjugate() * b).norm();
}

}  // namespace semslam::testing_optim
