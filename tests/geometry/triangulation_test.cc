#include "semslam/geometry/triangulation.h"

#include <gtest/gtest.h>

#include <numbers>

namespace semslam {
namespace {

TEST(Triangulation, RecoversPointFromTwoViews) {
  const Rigid3d world_from_cam1;
  const Rigid3d world_from_cam2(Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY())),
                                Eigen::Vector3d(1.0, 0.0, 0.2));
  const Eigen::Vector3d point(0.5, -0.4, 9.0);
  const Rigid3d cam1_from_world = world_from_cam1.Inverse();
  const Rigid3d cam2_from_world = world_from_cam2.Inverse();
  const auto x = TriangulatePoint(cam1_from_world, cam2_from_world, cam1_from_world * point, cam2_from_world * point);
  ASSERT_TRUE(x.has_value());
  EXPECT_TRUE(x->isApprox(point, 1e-9));
}

TEST(Triangulation, RejectsPointBehindCamera) {
  const Rigid3d cam1_from_world;
  const Rigid3d cam2_from_world = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)).Inverse();
  const Eigen::Vector3d behind(0.0, 0.0, -5.0);
  // Bearings pointing forward while the true intersection is behind both cameras.
  const auto x = TriangulatePoint(cam1_from_world, cam2_from_world, -(cam1_from_world * behind),
                                  -(cam2_from_world * behind));
  EXPECT_FALSE(x.has_value());
}

TEST(Triangulation, RejectsParallelRays) {
  const Rigid3d cam1_from_world;
  const Rigid3d cam2_from_world = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)).Inverse();
  const Eigen::Vector3d ray(0.0, 0.0, 1.0);
  EXPECT_FALSE(TriangulatePoint(cam1_from_world, cam2_from_world, ray, ray).has_value());
}

TEST(Triangulation, AngleOfSymmetricPair) {
  // Centres at x = -1 and x = +1, point at distance 1 ahead: rays at 45 degrees each, 90 degrees apart.
  EXPECT_NEAR(TriangulationAngle({-1, 0, 0}, {1, 0, 0}, {0, 0, 1}), std::numbers::pi / 2, 1e-12);
}

}  // namespace
}  // namespace semslam
