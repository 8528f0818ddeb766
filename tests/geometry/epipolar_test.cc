#include "semslam/geometry/epipolar.h"

#include <gtest/gtest.h>

#include <numbers>
#include <random>

#include "support/draws.h"

namespace semslam {
namespace {

using testing::DrawVector2;

const Rigid3d kCamera2FromCamera1(
    Eigen::Quaterniond(Eigen::AngleAxisd(0.08, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())),
    Eigen::Vector3d(-0.9, 0.1, -0.3));

Eigen::Vector2d Normalized(const Eigen::Vector3d& p) { return p.hnormalized(); }

double RotationErrorDeg(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.angularDistance(b) * 180.0 / std::numbers::pi;
}

// Points of a tilted plane n^T X = d seen by both cameras (normalized coordinates).
void PlanarScene(const Eigen::Vector3d& normal, double distance, int count, Points2d* x1, Points2d* x2) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d xy = DrawVector2(u, rng);
    const Eigen::Vector3d ray(xy.x(), xy.y(), 1.0);
    const Eigen::Vector3d point = distance / normal.dot(ray) * ray;
    x1->push_back(Normalized(point));
    x2->push_back(Normalized(kCamera2FromCamera1 * point));
  }
}

TEST(Epipolar, HartleyNormalizationCentresAndScales) {
  const Points2d points = {{10, 20}, {30, 20}, {20, 40}, {20, 0}};
  const Eigen::Matrix3d t = HartleyNormalization(points);
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  double mean = 0;
  for (const auto& p : points) centroid += (t * p.homogeneous()).hnormalized();
  for (const auto& p : points) mean += (t * p.homogeneous()).hnormalized().norm();
  EXPECT_LT(centroid.norm(), 1e-12);
  EXPECT_NEAR(mean / 4, std::sqrt(2.0), 1e-12);
}

TEST(Epipolar, HomographyFromFourAndManyPoints) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  Points2d x1, x2;
  PlanarScene(normal, 8.0, 30, &x1, &x2);
  const Eigen::Matrix3d truth = kCamera2FromCamera1.rotation.toRotationMatrix() +
                                kCamera2FromCamera1.translation * normal.transpose() / 8.0;
  for (const size_t count : {size_t{4}, size_t{30}}) {
    const Points2d a(x1.begin(), x1.begin() + static_cast<std::ptrdiff_t>(count));
    const Points2d b(x2.begin(), x2.begin() + static_cast<std::ptrdiff_t>(count));
    const auto h = EstimateHomography(a, b);
    ASSERT_TRUE(h.has_value());
    const Eigen::Matrix3d expected = truth / truth.norm() * (truth(2, 2) * (*h)(2, 2) > 0 ? 1.0 : -1.0);
    EXPECT_LT((*h - expected).norm(), 1e-9) << count;
  }
}

TEST(Epipolar, HomographyRejectsDegenerateSets) {
  EXPECT_FALSE(EstimateHomography({{0, 0}, {1, 0}, {0, 1}}, {{0, 0}, {1, 0}, {0, 1}}).has_value());
  // Three of four collinear.
  EXPECT_FALSE(
      EstimateHomography({{0, 0}, {1, 0}, {2, 0}, {0, 1}}, {{0, 0}, {1, 0}, {2, 0}, {0, 1}}).has_value());
}

TEST(Epipolar, DecompositionContainsTheTrueMotion) {
  const Eigen::Vector3d normal = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  const double distance = 8.0;
  const Eigen::Matrix3d h = kCamera2FromCamera1.rotation.toRotationMatrix() +
                            kCamera2FromCamera1.translation * normal.transpose() / distance;
  // Any scale and sign of H.
  for (const double scale : {1.0, -2.5}) {
    const auto motions = DecomposeHomography(scale * h);
    ASSERT_EQ(motions.size(), 8u);
    int found = 0;
    for (const auto& m : motions) {
      // Every hypothesis reproduces H up to scale.
      const Eigen::Matrix3d rebuilt = m.camera2_from_camera1.rotation.toRotationMatrix() +
                                      m.camera2_from_camera1.translation * m.normal.transpose();
      const double k = rebuilt.norm() / h.norm() * (rebuilt(2, 2) * h(2, 2) > 0 ? 1.0 : -1.0);
      EXPECT_LT((rebuilt - k * h).norm(), 1e-9);
      if (RotationErrorDeg(m.camera2_from_camera1.rotation, kCamera2FromCamera1.rotation) < 1e-6 &&
          (m.camera2_from_camera1.translation - kCamera2FromCamera1.translation / distance).norm() < 1e-9 &&
          (m.normal - normal).norm() < 1e-9) {
        ++found;
      }
    }
    EXPECT_GE(found, 1) << scale;
  }
}

TEST(Epipolar, PureRotationHomography) {
  const auto motions = DecomposeHomography(3.0 * kCamera2FromCamera1.rotation.toRotationMatrix());
  ASSERT_EQ(motions.size(), 1u);
  EXPECT_LT(RotationErrorDeg(motions[0].camera2_from_camera1.rotation, kCamera2FromCamera1.rotation), 1e-6);
  EXPECT_EQ(motions[0].camera2_from_camera1.translation.norm(), 0.0);
}

TEST(Epipolar, FundamentalFromEightAndManyPoints) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.5, 0.5), depth(4.0, 30.0);
  Points2d x1, x2;
  for (int i = 0; i < 40; ++i) {
    const Eigen::Vector2d xy = DrawVector2(u, rng);
    const Eigen::Vector3d point = depth(rng) * Eigen::Vector3d(xy.x(), xy.y(), 1.0);
    x1.push_back(Normalized(point));
    x2.push_back(Normalized(kCamera2FromCamera1 * point));
  }
  const Eigen::Matrix3d essential =
      SkewSymmetric(kCamera2FromCamera1.translation) * kCamera2FromCamera1.rotation.toRotationMatrix();
  for (const size_t count : {size_t{8}, size_t{40}}) {
    const Points2d a(x1.begin(), x1.begin() + static_cast<std::ptrdiff_t>(count));
    const Points2d b(x2.begin(), x2.begin() + static_cast<std::ptrdiff_t>(count));
    const auto f = EstimateFundamental(a, b);
    ASSERT_TRUE(f.has_value());
    EXPECT_NEAR(f->jacobiSvd().singularValues()(2), 0.0, 1e-12);
    for (size_t i = 0; i < x1.size(); ++i)
      EXPECT_NEAR(x2[i].homogeneous().dot(*f * x1[i].homogeneous()), 0.0, 1e-9);
    const double sign = essential(0, 1) * (*f)(0, 1) > 0 ? 1.0 : -1.0;
    EXPECT_LT((*f - sign * essential / essential.norm()).norm(), 1e-8);
  }
  EXPECT_FALSE(
      EstimateFundamental(Points2d(x1.begin(), x1.begin() + 7), Points2d(x2.begin(), x2.begin() + 7)));
}

TEST(Epipolar, EssentialDecompositionContainsTheTrueMotion) {
  const Eigen::Matrix3d essential =
      SkewSymmetric(kCamera2FromCamera1.translation) * kCamera2FromCamera1.rotation.toRotationMatrix();
  const auto motions = DecomposeEssential(-4.0 * essential);
  ASSERT_EQ(motions.size(), 4u);
  int found = 0;
  for (const auto& m : motions) {
    EXPECT_NEAR(m.translation.norm(), 1.0, 1e-12);
    EXPECT_NEAR(m.rotation.toRotationMatrix().determinant(), 1.0, 1e-12);
    if (RotationErrorDeg(m.rotation, kCamera2FromCamera1.rotation) < 1e-6 &&
        (m.translation - kCamera2FromCamera1.translation.normalized()).norm() < 1e-9) {
      ++found;
    }
  }
  EXPECT_EQ(found, 1);
}

TEST(Epipolar, RelativePoseRefinementReachesTheTruth) {
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> u(-0.5, 0.5), depth(4.0, 30.0);
  Points2d x1, x2;
  for (int i = 0; i < 60; ++i) {
    const Eigen::Vector2d xy = DrawVector2(u, rng);
    const Eigen::Vector3d point = depth(rng) * Eigen::Vector3d(xy.x(), xy.y(), 1.0);
    x1.push_back(Normalized(point));
    x2.push_back(Normalized(kCamera2FromCamera1 * point));
  }
  const Rigid3d truth(kCamera2FromCamera1.rotation, kCamera2FromCamera1.translation.normalized());
  Eigen::Vector6d perturbation;
  perturbation << 0.05, -0.04, 0.03, 0.01, -0.02, 0.015;
  Rigid3d start = Rigid3d::Exp(perturbation) * truth;
  start.translation = 2.0 * start.translation.normalized();  // the norm is kept
  const Rigid3d refined = RefineRelativePose(start, x1, x2, {}, 20);
  EXPECT_LT(RotationErrorDeg(refined.rotation, truth.rotation), 1e-5);
  EXPECT_NEAR(refined.translation.norm(), 2.0, 1e-12);
  EXPECT_LT((refined.translation.normalized() - truth.translation).norm(), 1e-6);
  const Eigen::Matrix3d e = SkewSymmetric(truth.translation) * truth.rotation.toRotationMatrix();
  for (size_t i = 0; i < x1.size(); ++i) EXPECT_NEAR(SampsonError(e, x1[i], x2[i]), 0.0, 1e-12);
  // Too few pairs: the start comes back.
  const Rigid3d same =
      RefineRelativePose(start, Points2d(x1.begin(), x1.begin() + 4), Points2d(x2.begin(), x2.begin() + 4));
  EXPECT_EQ(same.translation, start.translation);
}

TEST(Epipolar, SampsonErrorApproximatesPixelDistance) {
  // F = [e]x for a pure sideways translation: epipolar lines are horizontal, a vertical offset of 2 splits
  // evenly between the two images: Sampson error 2 / sqrt(2) per image, sqrt(2) in total.
  const Eigen::Matrix3d f = SkewSymmetric(Eigen::Vector3d(1, 0, 0));
  EXPECT_NEAR(std::abs(SampsonError(f, {0.3, 0.0}, {0.1, 2.0})), std::sqrt(2.0), 1e-12);
}

}  // namespace
}  // namespace semslam
