#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <Eigen/StdVector>
#include <vector>

namespace Eigen {
using Matrix3x4d = Matrix<double, 3, 4>;
using Matrix6d = Matrix<double, 6, 6>;
using Vector6d = Matrix<double, 6, 1>;
using Vector7d = Matrix<double, 7, 1>;
}  // namespace Eigen

namespace semslam {
// Containers of fixed-size vectorizable Eigen types; with C++17 aligned new the standard allocator is fine.
using Points3d = std::vector<Eigen::Vector3d>;
using Points2d = std::vector<Eigen::Vector2d>;
}  // namespace semslam
