#include "semslam/optim/sim3_optimization.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "semslam/core/error.h"
#include "support/draws.h"
#include "synthetic.h"

namespace semslam {
namespace {

using testing::DrawVector2;
using testing_optim::RandomVector;
using testing_optim::RotationError;

struct Scene {
  Sim3RefinementProblem problem;
  Sim3d truth;  // camera1_from_camera2
  std::vector<bool> outlier;
};

// Matches between two keyframes of maps whose scales differ by `scale`: points 5-30 m in front of camera 2,
// visible from camera 1 too; keypoints with pyramid-level noise; a fraction of the matches wrong (point2
// swapped for an unrelated point).
Scene MakeScene(int n, double scale, double outlier_fraction, double pixel_noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Scene s;
  s.problem.camera1 = s.problem.camera2 = KittiCamera();
  s.truth = Sim3d(scale, QuaternionExp(Eigen::Vector3d(0.01, 0.15, -0.02)), Eigen::Vector3d(0.8, 0.1, -1.5));
  std::uniform_int_distribution<int> level(0, 5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  while (static_cast<int>(s.problem.matches.size()) < n) {
    const Eigen::Vector3d p2 = testing_optim::RandomCameraPoint(rng, s.problem.camera2, 5.0, 30.0);
    const Eigen::Vector3d p1 = s.truth * p2;
    if (p1.z() < 1.0 || !s.problem.camera1.InImage(s.problem.camera1.Project(p1))) continue;
    const double sigma1 = std::pow(1.2, level(rng)), sigma2 = std::pow(1.2, level(rng));
    Sim3Match m;
    m.point1 = p1;
    m.point2 = p2;
    m.pixel1 = s.problem.camera1.Project(p1) + pixel_noise * sigma1 * DrawVector2(noise, rng);
    m.pixel2 = s.problem.camera2.Project(p2) + pixel_noise * sigma2 * DrawVector2(noise, rng);
    m.inv_sigma2_1 = 1.0 / (sigma1 * sigma1);
    m.inv_sigma2_2 = 1.0 / (sigma2 * sigma2);
    const bool bad = unit(rng) < outlier_fraction;
    if (bad) {
      // A wrong match: keyframe 2's point (and keypoint) belong elsewhere in the image.
      const Eigen::Vector3d other = testing_optim::RandomCameraPoint(rng, s.problem.camera2, 5.0, 30.0);
      if ((s.problem.camera2.Project(other) - m.pixel2).norm() < 50.0) continue;
      m.point2 = other;
      m.pixel2 = s.problem.camera2.Project(other);
    }
    s.problem.matches.push_back(m);
    s.outlier.push_back(bad);
  }
  return s;
}

Sim3d Perturbed(const Sim3d& s, double log_scale) {
  return Sim3d(std::exp(log_scale), QuaternionExp(Eigen::Vector3d(0.02, -0.03, 0.01)),
               Eigen::Vector3d(0.2, -0.1, 0.3)) *
         s;
}

TEST(OptimizeSim3, NoiseFreeIsExact) {
  const Scene s = MakeScene(60, 1.7, 0.0, 0.0, 1);
  const Sim3RefinementResult r = OptimizeSim3(s.problem, Perturbed(s.truth, 0.1), 10.0, false);
  EXPECT_NEAR(r.camera1_from_camera2.scale, 1.7, 1e-8);
  EXPECT_LT(RotationError(r.camera1_from_camera2.rotation, s.truth.rotation), 1e-9);
  EXPECT_LT((r.camera1_from_camera2.translation - s.truth.translation).norm(), 1e-8);
  EXPECT_EQ(r.num_inliers, 60);
}

TEST(OptimizeSim3, RecoversPerturbedSimilarityAndFlagsOutliers) {
  const Scene s = MakeScene(150, 0.6, 0.15, 1.0, 2);
  const Sim3RefinementResult r = OptimizeSim3(s.problem, Perturbed(s.truth, -0.08), 10.0, false);
  EXPECT_NEAR(r.camera1_from_camera2.scale, 0.6, 0.015);  // at worst 0.0084 over 60 seeds
  EXPECT_LT(RotationError(r.camera1_from_camera2.rotation, s.truth.rotation), 2e-3);
  EXPECT_LT((r.camera1_from_camera2.translation - s.truth.translation).norm(), 0.03);
  ASSERT_EQ(r.inliers.size(), s.outlier.size());
  int good = 0, kept = 0;
  for (size_t i = 0; i < s.outlier.size(); ++i) {
    if (s.outlier[i]) {
      EXPECT_FALSE(r.inliers[i]) << "wrong match " << i << " kept";
    } else {
      ++good;
      kept += r.inliers[i] ? 1 : 0;
    }
  }
  EXPECT_GT(kept, 0.95 * good);  // chi2 10 on 2 DoF rejects < 1 % of good matches
}

TEST(OptimizeSim3, FixedScaleStaysAtTheInitialScale) {
  const Scene s = MakeScene(100, 1.0, 0.1, 1.0, 3);
  const Sim3d initial =
      Sim3d(1.0, QuaternionExp(Eigen::Vector3d(0.02, -0.03, 0.01)), Eigen::Vector3d(0.2, -0.1, 0.3)) *
      s.truth;
  const Sim3RefinementResult r = OptimizeSim3(s.problem, initial, 10.0, true);
  EXPECT_DOUBLE_EQ(r.camera1_from_camera2.scale, 1.0);
  EXPECT_LT(RotationError(r.camera1_from_camera2.rotation, s.truth.rotation), 2e-3);
  EXPECT_LT((r.camera1_from_camera2.translation - s.truth.translation).norm(), 0.03);
}

TEST(OptimizeSim3, RejectsBadInput) {
  Scene s = MakeScene(10, 1.0, 0.0, 0.0, 4);
  EXPECT_THROW(OptimizeSim3(s.problem, s.truth, 0.0, false), InvalidArgument);
  EXPECT_THROW(OptimizeSim3(s.problem, Sim3d(-1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()),
                            10.0, false),
               InvalidArgument);
  s.problem.matches[2].inv_sigma2_2 = std::nan("");
  EXPECT_THROW(OptimizeSim3(s.problem, s.truth, 10.0, false), InvalidArgument);
  Sim3RefinementProblem empty;
  empty.camera1 = empty.camera2 = KittiCamera();
  EXPECT_TRUE(OptimizeSim3(empty, s.truth, 10.0, false).inliers.empty());
}

}  // namespace
}  // namespace semslam
