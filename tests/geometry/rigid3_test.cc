#include "semslam/geometry/rigid3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "semslam/geometry/sim3.h"

namespace semslam {
namespace {

Rigid3d RandomPose(int seed) {
  std::srand(seed);
  return Rigid3d(Eigen::Quaterniond::UnitRandom(), Eigen::Vector3d::Random() * 10.0);
}

TEST(Rigid3d, InverseComposesToIdentity) {
  const Rigid3d a = RandomPose(1);
  const Rigid3d identity = a * a.Inverse();
  EXPECT_LT(identity.translation.norm(), 1e-12);
  EXPECT_LT(identity.RotationAngle(), 1e-12);
}

TEST(Rigid3d, CompositionMatchesMatrices) {
  const Rigid3d a = RandomPose(2), b = RandomPose(3);
  const Eigen::Vector3d x(1.0, -2.0, 3.0);
  EXPECT_TRUE(((a * b) * x).isApprox(a * (b * x), 1e-12));
  EXPECT_TRUE((a * b).ToMatrix4().isApprox(a.ToMatrix4() * b.ToMatrix4(), 1e-12));
}

TEST(Rigid3d, KnownRotationMovesPoint) {
  // 90 degrees about z, then 1 m along x: (1,0,0) -> (0,1,0) -> (1,1,0).
  const Rigid3d t(Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ())),
                  Eigen::Vector3d(1, 0, 0));
  EXPECT_TRUE((t * Eigen::Vector3d(1, 0, 0)).isApprox(Eigen::Vector3d(1, 1, 0), 1e-12));
  EXPECT_NEAR(t.RotationAngle(), std::numbers::pi / 2, 1e-12);
}

TEST(Rigid3d, ExpLogRoundTrip) {
  Eigen::Vector6d twist;
  twist << 0.3, -1.2, 2.0, 0.4, -0.2, 0.9;
  const Rigid3d t = Rigid3d::Exp(twist);
  EXPECT_TRUE(t.Log().isApprox(twist, 1e-10));
  // Pure translation: exp is the translation itself.
  Eigen::Vector6d translation_only = Eigen::Vector6d::Zero();
  translation_only.head<3>() << 1, 2, 3;
  EXPECT_TRUE(Rigid3d::Exp(translation_only).translation.isApprox(Eigen::Vector3d(1, 2, 3)));
}

TEST(Rigid3d, FromMatrixOrthonormalizes) {
  Eigen::Matrix3x4d m = RandomPose(4).ToMatrix();
  m.leftCols<3>() *= 1.0 + 1e-7;  // text-file rounding
  const Rigid3d t = Rigid3d::FromMatrix(m);
  const Eigen::Matrix3d r = t.rotation.toRotationMatrix();
  EXPECT_TRUE((r * r.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_TRUE(t.translation.isApprox(m.col(3)));
}

TEST(Rigid3d, InterpolateHalfway) {
  const Rigid3d a;
  const Rigid3d b(Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitY())), Eigen::Vector3d(2, 0, 0));
  const Rigid3d mid = Interpolate(a, b, 0.5);
  EXPECT_NEAR(mid.RotationAngle(), 0.5, 1e-12);
  EXPECT_TRUE(mid.translation.isApprox(Eigen::Vector3d(1, 0, 0)));
}

TEST(Sim3d, InverseAndComposition) {
  const Sim3d s(2.5, Eigen::Quaterniond::UnitRandom(), Eigen::Vector3d(1, 2, 3));
  const Eigen::Vector3d x(-4, 5, 0.5);
  EXPECT_TRUE((s.Inverse() * (s * x)).isApprox(x, 1e-12));
  EXPECT_TRUE(((s * s) * x).isApprox(s * (s * x), 1e-12));
  EXPECT_NEAR((s * x - s.translation).norm(), 2.5 * x.norm(), 1e-9);
}

TEST(Sim3d, TransformPoseScalesPositionOnly) {
  const Sim3d s(3.0, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(1, 0, 0));
  const Rigid3d pose(Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX())), Eigen::Vector3d(0, 1, 0));
  const Rigid3d moved = s.TransformPose(pose);
  EXPECT_TRUE(moved.translation.isApprox(s * pose.translation));
  EXPECT_TRUE(moved.rotation.isApprox(s.rotation * pose.rotation));
  // A point fixed to the camera 1 m ahead maps consistently only up to scale: the direction is kept.
  const Eigen::Vector3d ahead_src = pose * Eigen::Vector3d(0, 0, 1) - pose.translation;
  const Eigen::Vector3d ahead_tgt = moved * Eigen::Vector3d(0, 0, 1) - moved.translation;
  EXPECT_TRUE((s.rotation * ahead_src).isApprox(ahead_tgt));
}

TEST(IsRotation, RoundingPassesScaleAndReflectionDoNot) {
  const Eigen::Matrix3d r = QuaternionExp(Eigen::Vector3d(0.3, -0.2, 1.1)).toRotationMatrix();
  EXPECT_NEAR(OrthonormalityDeviation(r), 0.0, 1e-12);
  EXPECT_TRUE(IsRotation(r));
  // Six significant digits, as text files give them.
  const Eigen::Matrix3d rounded = (r * 1e6).array().round() / 1e6;
  EXPECT_TRUE(IsRotation(rounded));
  EXPECT_FALSE(IsRotation(2.0 * r));  // deviation 3
  EXPECT_NEAR(OrthonormalityDeviation(2.0 * r), 3.0, 1e-9);
  EXPECT_FALSE(IsRotation(-r));  // orthonormal, determinant -1
  EXPECT_FALSE(IsRotation(Eigen::Matrix3d::Zero()));
  // What an error message says of each.
  EXPECT_FALSE(RotationDefect(rounded).has_value());
  EXPECT_EQ(RotationDefect(2.0 * r).value_or(""), "not orthonormal (largest |R^T R - I| entry 3)");
  EXPECT_EQ(RotationDefect(-r).value_or(""), "a reflection (determinant -1)");
}

}  // namespace
}  // namespace semslam
