#include "semslam/geometry/pnp.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "semslam/core/error.h"
#include "semslam/geometry/camera.h"
#include "support/draws.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

using testing::DrawVector2;
using testing::DrawVector3;

constexpr double kDeg = std::numbers::pi / 180.0;

Rigid3d RandomPose(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d axis = DrawVector3(n, rng).normalized();
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  const Eigen::Vector3d translation = 5 * DrawVector3(n, rng);  // before the angle, as GCC drew them
  return Rigid3d(Eigen::Quaterniond(Eigen::AngleAxisd(angle(rng), axis)), translation);
}

struct Correspondences {
  Rigid3d camera_from_world;
  Points3d world_points;
  Points3d bearings;
  std::vector<bool> outlier;
};

// Points visible in the test camera at depths 3..30 m, pixel noise, and a fraction of random bearings.
Correspondences MakeCorrespondences(int count, double noise_px, double outlier_ratio, unsigned seed) {
  const PinholeCamera camera = KittiCamera();
  std::mt19937 rng(seed);
  Correspondences c;
  c.camera_from_world = RandomPose(rng);
  const Rigid3d world_from_camera = c.camera_from_world.Inverse();
  std::uniform_real_distribution<double> u(0.0, camera.width - 1.0), v(0.0, camera.height - 1.0),
      depth(3.0, 30.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_px);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d pixel = DrawVector2(u, v, rng);
    c.world_points.push_back(world_from_camera * camera.UnprojectDepth(pixel, depth(rng)));
    const bool outlier = unit(rng) < outlier_ratio;
    c.outlier.push_back(outlier);
    const Eigen::Vector2d observed =
        outlier ? DrawVector2(u, v, rng) : Eigen::Vector2d(pixel + DrawVector2(noise, rng));
    c.bearings.push_back(camera.Unproject(observed));
  }
  return c;
}

double RotationErrorDeg(const Rigid3d& a, const Rigid3d& b) {
  return a.rotation.angularDistance(b.rotation) / kDeg;
}

TEST(P3P, ExactSolutionIsAmongTheCandidates) {
  std::mt19937 rng(1);
  int found = 0;
  const int trials = 500;
  for (int trial = 0; trial < trials; ++trial) {
    const Correspondences c = MakeCorrespondences(3, 0.0, 0.0, static_cast<unsigned>(trial));
    const auto poses = SolveP3P({c.world_points[0], c.world_points[1], c.world_points[2]},
                                {c.bearings[0], c.bearings[1], c.bearings[2]});
    EXPECT_LE(poses.size(), 4u);
    for (const Rigid3d& pose : poses) {
      if (RotationErrorDeg(pose, c.camera_from_world) < 1e-4 &&
          (pose.translation - c.camera_from_world.translation).norm() < 1e-5) {
        ++found;
        break;
      }
    }
  }
  // Near-degenerate draws (rays almost coplanar with the danger cylinder) may lose precision; nearly all
  // succeed.
  EXPECT_GE(found, trials * 99 / 100);
}

TEST(P3P, CollinearPointsGiveNothing) {
  const Rigid3d pose;
  const std::array<Eigen::Vector3d, 3> world = {Eigen::Vector3d(0, 0, 5), Eigen::Vector3d(1, 0, 6),
                                                Eigen::Vector3d(2, 0, 7)};
  EXPECT_TRUE(SolveP3P(world, world).empty());
}

TEST(PnpRansac, RecoversPoseWithNoiseAndOutliers) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Correspondences c = MakeCorrespondences(300, 0.5, 0.4, seed);
    PnpRansacOptions options;
    options.focal_length = KittiCamera().fx;
    options.seed = seed;
    const auto result = SolvePnpRansac(c.world_points, c.bearings, options);
    ASSERT_TRUE(result.has_value());
    EXPECT_LT(RotationErrorDeg(result->camera_from_world, c.camera_from_world), 0.1);
    const Eigen::Vector3d center = result->camera_from_world.Inverse().translation;
    const Eigen::Vector3d true_center = c.camera_from_world.Inverse().translation;
    EXPECT_LT((center - true_center).norm(), 0.01);
    int wrong = 0;
    for (size_t i = 0; i < c.outlier.size(); ++i) wrong += (result->inliers[i] == c.outlier[i]) ? 1 : 0;
    EXPECT_LT(wrong, 10);  // a random outlier may fall within the threshold
    EXPECT_EQ(result->num_inliers, std::count(result->inliers.begin(), result->inliers.end(), true));
    EXPECT_LT(result->rms_error_px, 1.5);
    EXPECT_LT(result->iterations, options.max_iterations);
  }
}

TEST(PnpRansac, RefinementReachesTheExactPose) {
  const Correspondences c = MakeCorrespondences(50, 0.0, 0.0, 4);
  Rigid3d start = c.camera_from_world;
  start = Rigid3d::Exp((Eigen::Vector6d() << 0.05, -0.03, 0.1, 0.01, 0.02, -0.01).finished()) * start;
  const Rigid3d refined = RefinePose(start, c.world_points, c.bearings);
  EXPECT_LT(RotationErrorDeg(refined, c.camera_from_world), 1e-6);
  EXPECT_LT((refined.translation - c.camera_from_world.translation).norm(), 1e-7);
}

TEST(PnpRansac, DeterministicForSeed) {
  const Correspondences c = MakeCorrespondences(200, 1.0, 0.5, 5);
  PnpRansacOptions options;
  options.focal_length = KittiCamera().fx;
  options.seed = 99;
  const auto a = SolvePnpRansac(c.world_points, c.bearings, options);
  const auto b = SolvePnpRansac(c.world_points, c.bearings, options);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->camera_from_world.translation, b->camera_from_world.translation);
  EXPECT_EQ(a->inliers, b->inliers);
}

TEST(PnpRansac, DegenerateOrTooFewGiveNothing) {
  PnpRansacOptions options;
  options.focal_length = KittiCamera().fx;
  // Too few correspondences.
  const Correspondences few = MakeCorrespondences(8, 0.0, 0.0, 6);
  EXPECT_FALSE(SolvePnpRansac(few.world_points, few.bearings, options).has_value());
  EXPECT_FALSE(SolvePnpRansac({}, {}, options).has_value());
  // All world points on one line.
  Points3d line, rays;
  for (int i = 0; i < 40; ++i) {
    line.emplace_back(0.1 * i - 2.0, 0.05 * i, 10.0 + 0.2 * i);
    rays.push_back(line.back().normalized());
  }
  EXPECT_FALSE(SolvePnpRansac(line, rays, options).has_value());
  // Only outliers.
  const Correspondences junk = MakeCorrespondences(100, 0.0, 1.0, 7);
  EXPECT_FALSE(SolvePnpRansac(junk.world_points, junk.bearings, options).has_value());
}

TEST(PnpRansac, BadInputThrows) {
  PnpRansacOptions options;
  options.focal_length = KittiCamera().fx;
  const Correspondences c = MakeCorrespondences(20, 0.0, 0.0, 8);
  EXPECT_THROW(SolvePnpRansac(c.world_points, Points3d(c.bearings.begin(), c.bearings.end() - 1), options),
               InvalidArgument);
  Points3d bad = c.world_points;
  bad[3].x() = std::nan("");
  EXPECT_THROW(SolvePnpRansac(bad, c.bearings, options), InvalidArgument);
  EXPECT_NO_THROW(SolvePnpRansac(c.world_points, c.bearings, options));
  options.focal_length = 0.0;  // not set
  EXPECT_THROW(SolvePnpRansac(c.world_points, c.bearings, options), InvalidArgument);
}

}  // namespace
}  // namespace semslam
