#include "semslam/geometry/alignment.h"

#include <gtest/gtest.h>

#include <random>

#include "support/draws.h"

namespace semslam {
namespace {

using testing::DrawVector3;

Points3d RandomCloud(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  Points3d points;
  for (int i = 0; i < n; ++i) points.push_back(DrawVector3(u, rng));
  return points;
}

TEST(Alignment, RecoversKnownSim3) {
  const Sim3d truth(0.37, Eigen::Quaterniond(Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, 3).normalized())),
                    Eigen::Vector3d(5, -2, 7));
  const Points3d src = RandomCloud(50, 7);
  Points3d tgt;
  for (const auto& p : src) tgt.push_back(truth * p);
  const auto est = AlignSim3(src, tgt);
  ASSERT_TRUE(est.has_value());
  EXPECT_NEAR(est->scale, 0.37, 1e-10);
  EXPECT_TRUE(est->rotation.isApprox(truth.rotation, 1e-10) || est->rotation.coeffs().isApprox(-truth.rotation.coeffs(), 1e-10));
  EXPECT_TRUE(est->translation.isApprox(truth.translation, 1e-9));
  EXPECT_LT(AlignmentRmse(*est, src, tgt), 1e-9);
}

TEST(Alignment, RigidKeepsScaleOne) {
  const Rigid3d truth(Eigen::Quaterniond(Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(1, 1, 1));
  const Points3d src = RandomCloud(10, 3);
  Points3d tgt;
  for (const auto& p : src) tgt.push_back(truth * p * 1.0);
  const auto est = AlignRigid3(src, tgt);
  ASSERT_TRUE(est.has_value());
  EXPECT_TRUE(est->translation.isApprox(truth.translation, 1e-9));
}

TEST(Alignment, ReflectionIsNotReturned) {
  // Mirrored target: the best proper rotation has det +1 even though a reflection would fit exactly.
  const Points3d src = RandomCloud(20, 11);
  Points3d tgt;
  for (const auto& p : src) tgt.emplace_back(-p.x(), p.y(), p.z());
  const auto est = AlignSim3(src, tgt);
  ASSERT_TRUE(est.has_value());
  EXPECT_NEAR(est->rotation.toRotationMatrix().determinant(), 1.0, 1e-9);
  EXPECT_GT(AlignmentRmse(*est, src, tgt), 1.0);
}

TEST(Alignment, ZeroWeightsIgnoreOutliers) {
  const Sim3d truth(2.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 1));
  const Points3d src = RandomCloud(12, 5);
  Points3d tgt;
  for (const auto& p : src) tgt.push_back(truth * p);
  tgt[3] += Eigen::Vector3d(50, 0, 0);
  std::vector<double> weights(src.size(), 1.0);
  weights[3] = 0.0;
  const auto est = AlignSim3(src, tgt, weights);
  ASSERT_TRUE(est.has_value());
  EXPECT_NEAR(est->scale, 2.0, 1e-9);
}

TEST(Alignment, DegenerateInputsGiveNothing) {
  EXPECT_FALSE(AlignSim3(RandomCloud(2, 1), RandomCloud(2, 2)).has_value());  // too few
  EXPECT_FALSE(AlignSim3(RandomCloud(5, 1), RandomCloud(4, 2)).has_value());  // sizes differ
  Points3d line;
  for (int i = 0; i < 6; ++i) line.emplace_back(i, 2.0 * i, 0.0);
  EXPECT_FALSE(AlignSim3(line, line).has_value());  // collinear
}

}  // namespace
}  // namespace semslam
