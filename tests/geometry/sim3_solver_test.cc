#include "semslam/geometry/sim3_solver.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "semslam/core/error.h"
#include "support/draws.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

using testing::DrawVector2;

constexpr double kDeg = std::numbers::pi / 180.0;

struct Matches {
  Sim3Correspondences correspondences;
  std::vector<bool> outlier;
};

// Map points seen by both keyframes (noisy keypoints at random pyramid levels, 3D points with 0.5 % depth
// noise), and wrong matches: the match's point in keyframe 2 is another point, with its own keypoint.
Matches MakeMatches(const Sim3d& camera1_from_camera2, int count, double outlier_ratio, unsigned seed) {
  Matches m;
  Sim3Correspondences& c = m.correspondences;
  c.camera1 = c.camera2 = KittiCamera();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, c.camera2.width - 1.0), v(0.0, c.camera2.height - 1.0);
  std::uniform_real_distribution<double> depth(4.0, 30.0), unit(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, 3);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto random_point2 = [&] {
    while (true) {
      const double z = depth(rng);  // before the pixel, as GCC drew them (support/draws.h)
      const Eigen::Vector3d p = c.camera2.UnprojectDepth({u(rng), v(rng)}, z);
      if (c.camera1.ProjectIfVisible(camera1_from_camera2 * p)) return p;
    }
  };
  const auto observe = [&](const PinholeCamera& camera, const Eigen::Vector3d& p, double* sigma2) {
    *sigma2 = std::pow(1.2, 2 * level(rng));
    const double sigma = std::sqrt(*sigma2);
    return Eigen::Vector2d(camera.Project(p) + sigma * DrawVector2(normal, rng));
  };
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p2 = random_point2();
    const Eigen::Vector3d p1 = camera1_from_camera2 * p2;
    double s1 = 0, s2 = 0;
    c.pixels1.push_back(observe(c.camera1, p1, &s1));
    c.points1.push_back(p1 * (1.0 + 0.005 * normal(rng)));
    const bool outlier = unit(rng) < outlier_ratio;
    const Eigen::Vector3d q2 = outlier ? random_point2() : p2;
    c.pixels2.push_back(observe(c.camera2, q2, &s2));
    c.points2.push_back(q2 * (1.0 + 0.005 * normal(rng)));
    c.sigma2_1.push_back(s1);
    c.sigma2_2.push_back(s2);
    m.outlier.push_back(outlier);
  }
  return m;
}

const Sim3d kTruth(1.3,
                   Eigen::Quaterniond(Eigen::AngleAxisd(10 * kDeg,
                                                        Eigen::Vector3d(0.1, 1.0, 0.2).normalized())),
                   Eigen::Vector3d(0.8, 0.1, -1.5));

void ExpectClose(const Sim3d& estimate, const Sim3d& truth, double scale_tolerance) {
  EXPECT_NEAR(estimate.scale / truth.scale, 1.0, scale_tolerance);
  EXPECT_LT(estimate.rotation.angularDistance(truth.rotation) / kDeg, 0.5);
  EXPECT_LT((estimate.translation - truth.translation).norm(), 0.03 * truth.translation.norm());
}

TEST(Sim3Ransac, RecoversSimilarityWithOutliers) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    const Matches m = MakeMatches(kTruth, 100, 0.3, seed);
    Sim3RansacOptions options;
    options.seed = seed;
    const auto result = EstimateSim3Ransac(m.correspondences, options);
    ASSERT_TRUE(result.has_value());
    ExpectClose(result->camera1_from_camera2, kTruth, 0.01);
    int wrong = 0;
    for (size_t i = 0; i < m.outlier.size(); ++i) wrong += (result->inliers[i] == m.outlier[i]) ? 1 : 0;
    EXPECT_LE(wrong, 8);
    EXPECT_EQ(result->num_inliers, std::count(result->inliers.begin(), result->inliers.end(), true));
  }
}

TEST(Sim3Ransac, FixedScaleIsRigid) {
  const Sim3d truth(1.0, kTruth.rotation, kTruth.translation);
  const Matches m = MakeMatches(truth, 100, 0.3, 4);
  Sim3RansacOptions options;
  options.fix_scale = true;
  const auto result = EstimateSim3Ransac(m.correspondences, options);
  ASSERT_TRUE(result.has_value());
  EXPECT_EQ(result->camera1_from_camera2.scale, 1.0);
  ExpectClose(result->camera1_from_camera2, truth, 1e-12);
  EXPECT_GE(result->num_inliers, 60);
}

TEST(Sim3Ransac, FixedScaleCannotExplainAScaledMap) {
  const Sim3d truth(2.0, kTruth.rotation, kTruth.translation);
  const Matches m = MakeMatches(truth, 100, 0.0, 5);
  Sim3RansacOptions options;
  options.fix_scale = true;
  options.min_inliers = 50;
  EXPECT_FALSE(EstimateSim3Ransac(m.correspondences, options).has_value());
  options.fix_scale = false;
  const auto free_scale = EstimateSim3Ransac(m.correspondences, options);
  ASSERT_TRUE(free_scale.has_value());
  EXPECT_NEAR(free_scale->camera1_from_camera2.scale, 2.0, 0.02);
}

TEST(Sim3Ransac, TooFewOrAllWrongGiveNothing) {
  Sim3RansacOptions options;
  const Matches few = MakeMatches(kTruth, 15, 0.0, 6);
  EXPECT_FALSE(EstimateSim3Ransac(few.correspondences, options).has_value());  // below min_inliers
  const Matches junk = MakeMatches(kTruth, 100, 1.0, 7);
  EXPECT_FALSE(EstimateSim3Ransac(junk.correspondences, options).has_value());
}

TEST(Sim3Ransac, BadInputThrows) {
  Matches m = MakeMatches(kTruth, 30, 0.0, 8);
  Sim3RansacOptions options;
  Sim3Correspondences c = m.correspondences;
  c.sigma2_2.pop_back();
  EXPECT_THROW(EstimateSim3Ransac(c, options), InvalidArgument);
  c = m.correspondences;
  c.sigma2_1[2] = 0.0;
  EXPECT_THROW(EstimateSim3Ransac(c, options), InvalidArgument);
  c = m.correspondences;
  c.points2[1].z() = std::nan("");
  EXPECT_THROW(EstimateSim3Ransac(c, options), InvalidArgument);
  options.min_inliers = 2;
  EXPECT_THROW(EstimateSim3Ransac(m.correspondences, options), InvalidArgument);
}

// Two keyframes taken from the same spot: reprojection cannot tell the true similarity from one whose scale
// (and translation) shrank to almost nothing, the 3D points can.
TEST(MedianDepthRatio, TellsACollapsedScaleThatReprojectionCannot) {
  const Sim3d truth(1.3, kTruth.rotation, Eigen::Vector3d::Zero());
  const Sim3d collapsed(0.001, kTruth.rotation, Eigen::Vector3d::Zero());
  const Matches m = MakeMatches(truth, 100, 0.2, 9);
  std::vector<bool> inliers;
  const int true_inliers = ClassifySim3Inliers(truth, m.correspondences, 9.21, &inliers);
  EXPECT_EQ(ClassifySim3Inliers(collapsed, m.correspondences, 9.21, &inliers), true_inliers);
  EXPECT_NEAR(MedianDepthRatio(truth, m.correspondences.points1, m.correspondences.points2), 1.0, 0.05);
  EXPECT_GT(MedianDepthRatio(collapsed, m.correspondences.points1, m.correspondences.points2), 1000.0);
  const Sim3d too_large(2.6, kTruth.rotation, Eigen::Vector3d::Zero());
  EXPECT_NEAR(MedianDepthRatio(too_large, m.correspondences.points1, m.correspondences.points2), 0.5, 0.05);
}

// The loop closer's refusal (factor 1.5) and the refinement's hold (1.15) both read a ratio this way:
// symmetric in ratio and 1/ratio, the bounds included, and nothing that is not a positive number passes.
TEST(DepthRatioWithin, IsSymmetricAboutOneAndRefusesNonNumbers) {
  EXPECT_TRUE(DepthRatioWithin(1.0, 1.15));
  EXPECT_TRUE(DepthRatioWithin(2.0, 2.0));  // the bounds, exactly representable
  EXPECT_TRUE(DepthRatioWithin(0.5, 2.0));
  EXPECT_FALSE(DepthRatioWithin(0.49, 2.0));
  EXPECT_TRUE(DepthRatioWithin(1.1, 1.15));
  EXPECT_TRUE(DepthRatioWithin(1.0 / 1.1, 1.15));
  EXPECT_FALSE(DepthRatioWithin(1.16, 1.15));
  EXPECT_FALSE(DepthRatioWithin(1.0 / 1.16, 1.15));
  EXPECT_TRUE(DepthRatioWithin(1.49, 1.5));  // the uninterrupted seed-4711 loop the hold caught at 1.15
  EXPECT_FALSE(DepthRatioWithin(1.49, 1.15));
  EXPECT_FALSE(DepthRatioWithin(0.0, 1.5));
  EXPECT_FALSE(DepthRatioWithin(-1.0, 1.5));
  EXPECT_FALSE(DepthRatioWithin(std::nan(""), 1.5));
  EXPECT_FALSE(DepthRatioWithin(std::numeric_limits<double>::infinity(), 1.5));
}

TEST(MedianDepthRatio, BadInputThrows) {
  const Matches m = MakeMatches(kTruth, 10, 0.0, 10);
  Points3d points2 = m.correspondences.points2;
  points2.pop_back();
  EXPECT_THROW(MedianDepthRatio(kTruth, m.correspondences.points1, points2), InvalidArgument);
  EXPECT_THROW(MedianDepthRatio(kTruth, {}, {}), InvalidArgument);
  points2 = m.correspondences.points2;
  points2[3].x() = std::nan("");
  EXPECT_THROW(MedianDepthRatio(kTruth, m.correspondences.points1, points2), InvalidArgument);
}

}  // namespace
}  // namespace semslam
