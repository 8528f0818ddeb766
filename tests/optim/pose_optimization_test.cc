#include "semslam/optim/pose_optimization.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "semslam/core/error.h"
#include "support/draws.h"
#include "synthetic.h"

namespace semslam {
namespace {

using testing::DrawVector2;
using testing_optim::Perturbation;
using testing_optim::RotationError;

constexpr double kBaseline = 0.54;

struct Scene {
  PoseOptimizationProblem problem;  // initial pose perturbed
  Rigid3d truth;
  std::vector<bool> outlier;  // injected
};

// n observations of points 4-40 m in front of the true camera, keypoints on pyramid levels 0-7 (scale 1.2)
// with noise of their level's sigma, a fraction of them replaced by wrong matches (>= 40 px off).
Scene MakeScene(int n, bool stereo, double outlier_fraction, double pixel_noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  Scene s;
  s.problem.camera = KittiCamera();
  s.problem.baseline = stereo ? kBaseline : 0.0;
  s.truth = Rigid3d(QuaternionExp(Eigen::Vector3d(0.02, -0.3, 0.01)), Eigen::Vector3d(1.0, -0.2, 3.0));
  const Rigid3d world_from_camera = s.truth.Inverse();
  std::uniform_int_distribution<int> level(0, 7);
  std::uniform_real_distribution<double> unit(0.0, 1.0), angle(0.0, 2.0 * M_PI), offset(40.0, 150.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double bf = s.problem.camera.fx * kBaseline;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d pc = testing_optim::RandomCameraPoint(rng, s.problem.camera, 4.0, 40.0);
    const double sigma = std::pow(1.2, level(rng));
    PoseObservation o;
    o.point = world_from_camera * pc;
    o.inv_sigma2 = 1.0 / (sigma * sigma);
    o.pixel = s.problem.camera.Project(pc) + pixel_noise * sigma * DrawVector2(noise, rng);
    if (stereo) o.right_u = s.problem.camera.Project(pc).x() - bf / pc.z() + pixel_noise * sigma * noise(rng);
    const bool bad = unit(rng) < outlier_fraction;
    if (bad) {
      const double a = angle(rng), r = offset(rng);
      o.pixel += r * Eigen::Vector2d(std::cos(a), std::sin(a));
      if (stereo) o.right_u = std::max(0.0, o.right_u + r * std::cos(a));
    }
    s.problem.observations.push_back(o);
    s.outlier.push_back(bad);
  }
  s.problem.camera_from_world = Perturbation(rng, 0.05, 0.3) * s.truth;
  return s;
}

void ExpectRecovered(const Scene& s, const PoseOptimizationResult& r, double max_angle, double max_distance) {
  EXPECT_LT(RotationError(r.camera_from_world.rotation, s.truth.rotation), max_angle);
  EXPECT_LT((r.camera_from_world.translation - s.truth.translation).norm(), max_distance);
  ASSERT_EQ(r.inliers.size(), s.outlier.size());
  int good = 0, good_kept = 0, count = 0;
  for (size_t i = 0; i < s.outlier.size(); ++i) {
    if (s.outlier[i]) {
      EXPECT_FALSE(r.inliers[i]) << "injected outlier " << i << " kept";
    } else {
      ++good;
      good_kept += r.inliers[i] ? 1 : 0;
    }
    count += r.inliers[i] ? 1 : 0;
  }
  EXPECT_EQ(count, r.num_inliers);
  // The chi-square test at 95 % rejects about 5 % of the good observations (at worst 8 % over 60 seeds).
  EXPECT_GT(good_kept, 0.88 * good);
}

TEST(OptimizePose, NoiseFreeMonocularIsExact) {
  const Scene s = MakeScene(200, false, 0.0, 0.0, 1);
  const PoseOptimizationResult r = OptimizePose(s.problem);
  EXPECT_LT(RotationError(r.camera_from_world.rotation, s.truth.rotation), 1e-9);
  EXPECT_LT((r.camera_from_world.translation - s.truth.translation).norm(), 1e-8);
  EXPECT_EQ(r.num_inliers, 200);
}

TEST(OptimizePose, MonocularRecoversPoseAndFlagsOutliers) {
  const Scene s = MakeScene(500, false, 0.2, 1.0, 2);
  ExpectRecovered(s, OptimizePose(s.problem), 2e-3, 0.03);
}

TEST(OptimizePose, StereoRecoversPoseAndFlagsOutliers) {
  const Scene s = MakeScene(500, true, 0.2, 1.0, 3);
  ExpectRecovered(s, OptimizePose(s.problem), 2e-3, 0.02);
}

TEST(OptimizePose, CeresAndGaussNewtonAgree) {
  for (const bool stereo : {false, true}) {
    const Scene s = MakeScene(300, stereo, 0.1, 1.0, 4);
    PoseOptimizationOptions options;
    const PoseOptimizationResult gn = OptimizePose(s.problem, options);
    options.solver = PoseSolver::kCeres;
    const PoseOptimizationResult ceres = OptimizePose(s.problem, options);
    ExpectRecovered(s, ceres, 2e-3, 0.03);
    EXPECT_LT(RotationError(gn.camera_from_world.rotation, ceres.camera_from_world.rotation), 1e-5);
    EXPECT_LT((gn.camera_from_world.translation - ceres.camera_from_world.translation).norm(), 1e-4);
    EXPECT_EQ(gn.inliers, ceres.inliers);
  }
}

TEST(OptimizePose, OutliersComeBackWhenTheyFitAgain) {
  // Far from the truth, the first round's test rejects good observations; later rounds re-admit them.
  Scene s = MakeScene(300, false, 0.0, 0.5, 5);
  std::mt19937 rng(6);
  s.problem.camera_from_world = Perturbation(rng, 0.1, 1.0) * s.truth;
  const PoseOptimizationResult r = OptimizePose(s.problem);
  EXPECT_LT((r.camera_from_world.translation - s.truth.translation).norm(), 0.02);
  EXPECT_GT(r.num_inliers, 270);
}

TEST(OptimizePose, PointsBehindTheCameraAreOutliers) {
  Scene s = MakeScene(100, false, 0.0, 0.5, 7);
  PoseObservation behind = s.problem.observations[0];
  behind.point = s.truth.Inverse() * Eigen::Vector3d(0.5, 0.2, -5.0);
  s.problem.observations.push_back(behind);
  const PoseOptimizationResult r = OptimizePose(s.problem);
  EXPECT_FALSE(r.inliers.back());
  EXPECT_LT((r.camera_from_world.translation - s.truth.translation).norm(), 0.05);
}

TEST(OptimizePose, EmptyProblemReturnsTheInitialPose) {
  PoseOptimizationProblem p;
  p.camera = KittiCamera();
  p.camera_from_world = Rigid3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 3));
  const PoseOptimizationResult r = OptimizePose(p);
  EXPECT_TRUE(r.inliers.empty());
  EXPECT_EQ(r.camera_from_world.translation, p.camera_from_world.translation);
}

TEST(OptimizePose, RejectsBadInput) {
  Scene s = MakeScene(20, false, 0.0, 0.5, 8);
  PoseOptimizationProblem p = s.problem;
  p.observations[3].point.x() = std::nan("");
  EXPECT_THROW(OptimizePose(p), InvalidArgument);
  p = s.problem;
  p.observations[3].inv_sigma2 = 0.0;
  EXPECT_THROW(OptimizePose(p), InvalidArgument);
  p = s.problem;
  p.observations[3].right_u = 100.0;  // stereo without a baseline
  EXPECT_THROW(OptimizePose(p), InvalidArgument);
  p = s.problem;
  p.camera.distortion.k1 = 0.1;
  EXPECT_THROW(OptimizePose(p), InvalidArgument);
  PoseOptimizationOptions options;
  options.rounds = 0;
  EXPECT_THROW(OptimizePose(s.problem, options), InvalidArgument);
}

}  // namespace
}  // namespace semslam
