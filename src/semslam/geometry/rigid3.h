#pragma once
// Rigid transforms in 3D (SE(3)). Named for the frames they map between: `world_from_camera` maps
// points from the camera frame into the world frame, so camera centres are world_from_camera.translation.

#include <optional>
#include <string>

#include "semslam/geometry/eigen_types.h"

namespace semslam {

struct Rigid3d {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3d() = default;
  Rigid3d(const Eigen::Quaterniond& r, const Eigen::Vector3d& t) : rotation(r.normalized()), translation(t) {}
  Rigid3d(const Eigen::Matrix3d& r, const Eigen::Vector3d& t);

  // From [R|t]; R is re-orthonormalized (text files carry ~1e-9 rounding).
  static Rigid3d FromMatrix(const Eigen::Matrix3x4d& matrix);
  Eigen::Matrix3x4d ToMatrix() const;
  Eigen::Matrix4d ToMatrix4() const;

  Rigid3d Inverse() const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& point) const { return rotation * point + translation; }
  Rigid3d operator*(const Rigid3d& other) const;

  // Exponential map of a twist [rho; phi] (translation part first, rotation vector second).
  static Rigid3d Exp(const Eigen::Vector6d& twist);
  Eigen::Vector6d Log() const;

  // Rotation angle in radians (0..pi).
  double RotationAngle() const;
};

// Largest |R^T R - I| entry: how far `r` is from orthonormal.
double OrthonormalityDeviation(const Eigen::Matrix3d& r);
// Whether a matrix read from a file or given by a caller is a rotation: orthonormal within `tolerance` (text
// files carry rounding, which FromMatrix removes) and not a reflection.
inline constexpr double kRotationTolerance = 1e-2;
bool IsRotation(const Eigen::Matrix3d& r, double tolerance = kRotationTolerance);
// Why `r` is not a rotation, for an error message ("not orthonormal (...)" or "a reflection (...)"); empty
// when IsRotation(r, tolerance).
std::optional<std::string> RotationDefect(const Eigen::Matrix3d& r, double tolerance = kRotationTolerance);

// SO(3) helpers on rotation vectors.
Eigen::Matrix3d SkewSymmetric(const Eigen::Vector3d& v);
Eigen::Quaterniond QuaternionExp(const Eigen::Vector3d& rotation_vector);
Eigen::Vector3d QuaternionLog(const Eigen::Quaterniond& q);

// Geodesic interpolation: alpha = 0 gives a, alpha = 1 gives b.
Rigid3d Interpolate(const Rigid3d& a, const Rigid3d& b, double alpha);

// `a_from_b` with its translation stretched by `scale`: a relative pose carried into units `scale` times larger
// (a monocular map rescaled around it).
Rigid3d Stretched(const Rigid3d& a_from_b, double scale);

}  // namespace semslam
