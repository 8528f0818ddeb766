// The analytic Jacobians of every cost function against central differences taken through the manifolds'
// Plus (the tangent-space derivative that the "lifted" Jacobians must equal), and the manifolds themselves.

#include <gtest/gtest.h>

#include <memory>
#include <random>
#include <utility>
#include <vector>

#include "semslam/optim/cost_functions.h"
#include "semslam/optim/manifolds.h"
#include "synthetic.h"

namespace semslam {
namespace {

using optim_internal::kRigidSize;
using optim_internal::kSim3Size;
using testing_optim::RandomRigid;
using testing_optim::RandomVector;

// Evaluates `cost` at `params`; returns residuals and, when asked, the ambient Jacobians.
Eigen::VectorXd Evaluate(const ceres::CostFunction& cost, const std::vector<std::vector<double>>& params,
                         std::vector<Eigen::MatrixXd>* jacobians) {
  std::vector<const double*> blocks;
  for (const auto& p : params) blocks.push_back(p.data());
  Eigen::VectorXd r(cost.num_residuals());
  std::vector<std::vector<double>> storage;
  std::vector<double*> jac_ptrs;
  if (jacobians != nullptr) {
    for (size_t k = 0; k < params.size(); ++k) {
      storage.emplace_back(static_cast<size_t>(cost.num_residuals()) * params[k].size());
    }
    for (auto& s : storage) jac_ptrs.push_back(s.data());
  }
  EXPECT_TRUE(cost.Evaluate(blocks.data(), r.data(), jacobians != nullptr ? jac_ptrs.data() : nullptr));
  if (jacobians != nullptr) {
    jacobians->clear();
    for (size_t k = 0; k < params.size(); ++k) {
      const int cols = static_cast<int>(params[k].size());
      jacobians->push_back(
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
              storage[k].data(), cost.num_residuals(), cols));
    }
  }
  return r;
}

void ExpectJacobiansMatch(const ceres::CostFunction& cost, const std::vector<std::vector<double>>& params,
                          const std::vector<const ceres::Manifold*>& manifolds, double tolerance = 1e-6) {
  std::vector<Eigen::MatrixXd> analytic;
  Evaluate(cost, params, &analytic);
  for (size_t k = 0; k < params.size(); ++k) {
    const ceres::Manifold* m = manifolds[k];
    const int tangent = m != nullptr ? m->TangentSize() : static_cast<int>(params[k].size());
    // Lifted convention: the last ambient column (past the full tangent) is zero. (With the scale fixed, the
    // scale column is still filled but dropped by PlusJacobian.)
    if (m != nullptr) {
      EXPECT_EQ(analytic[k].col(analytic[k].cols() - 1).norm(), 0.0) << "block " << k;
    }
    for (int d = 0; d < tangent; ++d) {
      const double h = 1e-6;
      std::vector<double> delta(static_cast<size_t>(tangent), 0.0);
      auto shifted = [&](double step) {
        delta[static_cast<size_t>(d)] = step;
        std::vector<std::vector<double>> p = params;
        if (m != nullptr) {
          m->Plus(params[k].data(), delta.data(), p[k].data());
        } else {
          p[k][static_cast<size_t>(d)] += step;
        }
        return Evaluate(cost, p, nullptr);
      };
      const Eigen::VectorXd numeric = (shifted(h) - shifted(-h)) / (2 * h);
      const Eigen::VectorXd exact = analytic[k].col(d);
      EXPECT_LT((numeric - exact).norm(), tolerance * std::max(1.0, exact.norm()))
          << "block " << k << " direction " << d << "\nnumeric " << numeric.transpose() << "\nanalytic "
          << exact.transpose();
    }
  }
}

std::vector<double> Packed(const Rigid3d& t) {
  std::vector<double> x(kRigidSize);
  optim_internal::PackRigid(t, x.data());
  return x;
}

std::vector<double> Packed(const Sim3d& s) {
  std::vector<double> x(kSim3Size);
  optim_internal::PackSim3(s, x.data());
  return x;
}

Sim3d RandomSim3(std::mt19937& rng, double log_scale_sigma) {
  std::normal_distribution<double> n(0.0, log_scale_sigma);
  const Rigid3d motion = RandomRigid(rng, 0.8, 5.0);
  return Sim3d(std::exp(n(rng)), motion.rotation, motion.translation);
}

// A random camera pose and a world point 3-30 m in front of it.
std::pair<Rigid3d, Eigen::Vector3d> RandomPoseAndPoint(std::mt19937& rng, const PinholeCamera& camera) {
  const Rigid3d camera_from_world = RandomRigid(rng, 0.5, 2.0);
  return {camera_from_world,
          camera_from_world.Inverse() * testing_optim::RandomCameraPoint(rng, camera, 3, 30)};
}

TEST(OptimJacobians, Reprojection) {
  std::mt19937 rng(1);
  const PinholeCamera camera = KittiCamera();
  const optim_internal::RigidLeftManifold manifold;
  for (int trial = 0; trial < 5; ++trial) {
    const auto [camera_from_world, world] = RandomPoseAndPoint(rng, camera);
    for (const double right_u : {-1.0, 300.0}) {
      std::unique_ptr<ceres::CostFunction> cost(optim_internal::NewReprojectionCost(
          camera, camera.fx * 0.54, Eigen::Vector2d(600, 180), right_u, 0.8));
      ExpectJacobiansMatch(*cost, {Packed(camera_from_world), {world.x(), world.y(), world.z()}},
                           {&manifold, nullptr});
    }
  }
}

TEST(OptimJacobians, PosePrior) {
  std::mt19937 rng(4);
  const optim_internal::RigidLeftManifold manifold;
  for (int trial = 0; trial < 5; ++trial) {
    const Rigid3d a = RandomRigid(rng, 0.5, 2.0);
    const Rigid3d b = RandomRigid(rng, 0.5, 2.0);
    const Rigid3d measured = RandomRigid(rng, 0.1, 0.3) * a * b.Inverse();
    std::unique_ptr<ceres::CostFunction> cost(optim_internal::NewPosePriorCost(measured, 0.2, 0.05));
    ExpectJacobiansMatch(*cost, {Packed(a), Packed(b)}, {&manifold, &manifold});
  }
}

TEST(OptimJacobians, SelfCalibratingReprojection) {
  std::mt19937 rng(3);
  const PinholeCamera camera = KittiCamera();
  const optim_internal::RigidLeftManifold manifold;
  for (int trial = 0; trial < 5; ++trial) {
    const auto [camera_from_world, world] = RandomPoseAndPoint(rng, camera);
    // [f, cx, cy, k1, k2]: the nominal camera, then one with distortion of both signs.
    const std::vector<std::vector<double>> intrinsics = {
        {camera.fx, camera.cx, camera.cy, 0.0, 0.0},
        {0.98 * camera.fx, camera.cx + 4, camera.cy - 3, 0.05, -0.02}};
    for (const std::vector<double>& k : intrinsics) {
      std::unique_ptr<ceres::CostFunction> cost(
          optim_internal::NewSelfCalibratingReprojectionCost(Eigen::Vector2d(600, 180), 1.01, 0.8));
      ExpectJacobiansMatch(*cost, {Packed(camera_from_world), {world.x(), world.y(), world.z()}, k},
                           {&manifold, nullptr, nullptr});
    }
  }
}

TEST(OptimJacobians, RelativeSim3) {
  std::mt19937 rng(2);
  const optim_internal::Sim3RightManifold free_scale(false), fixed_scale(true);
  for (int trial = 0; trial < 5; ++trial) {
    const Sim3d a = RandomSim3(rng, 0.3), b = RandomSim3(rng, 0.3);
    // A measurement near the truth (small residual) and one far from it (large rotation residual).
    const Sim3d exact = a.Inverse() * b;
    const Sim3d noisy = exact * RandomSim3(rng, 0.1);
    for (const Sim3d& measured : {exact, noisy}) {
      Eigen::Matrix<double, 7, 7> sqrt_information = Eigen::Matrix<double, 7, 7>::Identity() * 1.5;
      std::unique_ptr<ceres::CostFunction> cost(
          optim_internal::NewRelativeSim3Cost(measured, sqrt_information));
      ExpectJacobiansMatch(*cost, {Packed(a), Packed(b)}, {&free_scale, &free_scale});
      ExpectJacobiansMatch(*cost, {Packed(a), Packed(b)}, {&fixed_scale, &fixed_scale});
      // A full (upper triangular) square root of the information.
      sqrt_information =
          sqrt_information.triangularView<Eigen::Upper>().toDenseMatrix() +
          0.3 * Eigen::Matrix<double, 7, 7>::Ones().triangularView<Eigen::StrictlyUpper>().toDenseMatrix();
      std::unique_ptr<ceres::CostFunction> full(
          optim_internal::NewRelativeSim3Cost(measured, sqrt_information));
      ExpectJacobiansMatch(*full, {Packed(a), Packed(b)}, {&free_scale, &free_scale});
    }
  }
}

TEST(OptimJacobians, PositionPriors) {
  std::mt19937 rng(3);
  const optim_internal::Sim3RightManifold manifold(false);
  for (int trial = 0; trial < 5; ++trial) {
    const Sim3d node = RandomSim3(rng, 0.3), frame = RandomSim3(rng, 0.3);
    const Eigen::Vector3d target = RandomVector(rng, 10.0);
    std::unique_ptr<ceres::CostFunction> plain(optim_internal::NewPositionPriorCost(target, 1.5, false));
    ExpectJacobiansMatch(*plain, {Packed(node)}, {&manifold});
    // On a point beside the node (a GPS antenna beside the camera).
    std::unique_ptr<ceres::CostFunction> offset(
        optim_internal::NewPositionPriorCost(target, 1.5, false, RandomVector(rng, 1.0)));
    ExpectJacobiansMatch(*offset, {Packed(node)}, {&manifold});
    std::unique_ptr<ceres::CostFunction> framed(optim_internal::NewPositionPriorCost(target, 1.5, true));
    ExpectJacobiansMatch(*framed, {Packed(node), Packed(frame)}, {&manifold, &manifold});
    const Eigen::Vector3d target_direction = RandomVector(rng, 1.0).normalized();  // GCC's order (draws.h)
    const Eigen::Vector3d axis = RandomVector(rng, 1.0).normalized();
    std::unique_ptr<ceres::CostFunction> direction(
        optim_internal::NewDirectionPriorCost(axis, target_direction, 0.05));
    ExpectJacobiansMatch(*direction, {Packed(node)}, {&manifold});
  }
}

TEST(OptimJacobians, Sim3Reprojection) {
  std::mt19937 rng(4);
  const PinholeCamera camera = KittiCamera();
  const optim_internal::Sim3RightManifold manifold(false);
  for (int trial = 0; trial < 5; ++trial) {
    const Rigid3d motion = RandomRigid(rng, 0.1, 0.5);
    const Sim3d c1_from_c2(std::exp(0.2 * trial - 0.4), motion.rotation, motion.translation);
    const Eigen::Vector3d p2 = testing_optim::RandomCameraPoint(rng, camera, 5, 20);
    const Eigen::Vector3d p1 = c1_from_c2 * p2;
    std::unique_ptr<ceres::CostFunction> into1(
        optim_internal::NewSim3ReprojectionCost(camera, p2, Eigen::Vector2d(500, 200), 0.7, true));
    ExpectJacobiansMatch(*into1, {Packed(c1_from_c2)}, {&manifold});
    std::unique_ptr<ceres::CostFunction> into2(
        optim_internal::NewSim3ReprojectionCost(camera, p1, Eigen::Vector2d(500, 200), 0.7, false));
    ExpectJacobiansMatch(*into2, {Packed(c1_from_c2)}, {&manifold});
  }
}

// A trial step to an overflowing scale (seen: log-scale 9292 in a loop's Sim(3) refinement) is refused, not
// evaluated to NaN residuals.
TEST(OptimJacobians, Sim3ReprojectionRefusesAnOverflowingScale) {
  const PinholeCamera camera = KittiCamera();
  std::unique_ptr<ceres::CostFunction> into1(optim_internal::NewSim3ReprojectionCost(
      camera, Eigen::Vector3d(0.5, -0.2, 10.0), Eigen::Vector2d(500, 200), 0.7, true));
  std::vector<double> x = Packed(Sim3d());
  const double* parameters[] = {x.data()};
  double residuals[2];
  EXPECT_TRUE(into1->Evaluate(parameters, residuals, nullptr));
  x[7] = 9292.0;
  EXPECT_FALSE(into1->Evaluate(parameters, residuals, nullptr));
}

TEST(OptimManifolds, PlusMinusRoundTrip) {
  std::mt19937 rng(5);
  const optim_internal::RigidLeftManifold rigid;
  const optim_internal::Sim3RightManifold sim3(false);
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> x = Packed(RandomRigid(rng, 1.0, 3.0));
    Eigen::Vector6d delta;
    delta.head<3>() = RandomVector(rng, 0.5);
    delta.tail<3>() = RandomVector(rng, 0.3);
    std::vector<double> y(kRigidSize);
    rigid.Plus(x.data(), delta.data(), y.data());
    Eigen::Vector6d back;
    rigid.Minus(y.data(), x.data(), back.data());
    EXPECT_LT((back - delta).norm(), 1e-12);
    // The left perturbation: y = [Exp(phi) | rho] * x.
    const Rigid3d expected =
        Rigid3d(QuaternionExp(delta.tail<3>()), delta.head<3>()) * optim_internal::UnpackRigid(x.data());
    const Rigid3d got = optim_internal::UnpackRigid(y.data());
    EXPECT_LT((got.translation - expected.translation).norm(), 1e-12);
    EXPECT_LT(testing_optim::RotationError(got.rotation, expected.rotation), 1e-12);

    const std::vector<double> s = Packed(RandomSim3(rng, 0.5));
    Eigen::Vector7d d7;
    d7.head<3>() = RandomVector(rng, 0.5);
    d7.segment<3>(3) = RandomVector(rng, 0.3);
    d7(6) = 0.2;
    std::vector<double> z(kSim3Size);
    sim3.Plus(s.data(), d7.data(), z.data());
    Eigen::Vector7d back7;
    sim3.Minus(z.data(), s.data(), back7.data());
    EXPECT_LT((back7 - d7).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace semslam
