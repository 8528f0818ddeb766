#include "semslam/optim/sim3_optimization.h"

#include <ceres/ceres.h>

#include <cmath>
#include <string>

#include "semslam/core/error.h"
#include "semslam/optim/cost_functions.h"
#include "semslam/optim/internal.h"
#include "semslam/optim/manifolds.h"

namespace semslam {

void Sim3RefinementOptions::Check() const {
  Require(iterations >= 1, "sim3 refinement: iterations must be >= 1");
  Require(refine_iterations >= 1, "sim3 refinement: refine_iterations must be >= 1");
}

namespace {

using optim_internal::kSim3Size;
using RowMajor2x8 = Eigen::Matrix<double, 2, kSim3Size, Eigen::RowMajor>;

// Whitened d(pixel)/d(camera point) of a pinhole, and the residual (prediction - measurement).
Eigen::Matrix<double, 2, 3> ProjectionJacobian(const PinholeCamera& c, const Eigen::Vector3d& p,
                                               double sqrt_info) {
  const double iz = 1.0 / p.z();
  const double s = sqrt_info * iz;
  Eigen::Matrix<double, 2, 3> a;
  a << s * c.fx, 0.0, -s * c.fx * p.x() * iz, 0.0, s * c.fy, -s * c.fy * p.y() * iz;
  return a;
}

void ProjectionResidual(const PinholeCamera& c, const Eigen::Vector3d& p, const Eigen::Vector2d& pixel,
                        double sqrt_info, double* e) {
  e[0] = sqrt_info * (c.fx * p.x() / p.z() + c.cx - pixel.x());
  e[1] = sqrt_info * (c.fy * p.y() / p.z() + c.cy - pixel.y());
}

// point2 seen in image 1: p1 = S * point2, S = camera1_from_camera2 (right perturbation:
// dp1/d[rho, phi, sigma] = s R [I, -[point2]x, point2]).
class Into1Cost final : public ceres::SizedCostFunction<2, kSim3Size> {
 public:
  Into1Cost(const PinholeCamera& camera, const Eigen::Vector3d& point2, const Eigen::Vector2d& pixel1,
            double sqrt_info)
      : camera_(camera), point_(point2), pixel_(pixel1), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const double s = std::exp(parameters[0][7]);
    const Eigen::Vector3d p = s * (q * point_) + t;
    if (!optim_internal::InFrontOfCamera(p)) return false;
    ProjectionResidual(camera_, p, pixel_, sqrt_info_, residuals);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      const Eigen::Matrix<double, 2, 3> a =
          ProjectionJacobian(camera_, p, sqrt_info_) * (s * q.toRotationMatrix());
      Eigen::Map<RowMajor2x8> j(jacobians[0]);
      j.block<2, 3>(0, 0) = a;
      j.block<2, 3>(0, 3) = -a * SkewSymmetric(point_);
      j.block<2, 1>(0, 6) = a * point_;
      j.col(7).setZero();
    }
    return true;
  }

 private:
  PinholeCamera camera_;
  Eigen::Vector3d point_;
  Eigen::Vector2d pixel_;
  double sqrt_info_;
};

// point1 seen in image 2: p2 = S^-1 * point1 (dp2/d[rho, phi, sigma] = [-I, [p2]x, -p2]).
class Into2Cost final : public ceres::SizedCostFunction<2, kSim3Size> {
 public:
  Into2Cost(const PinholeCamera& camera, const Eigen::Vector3d& point1, const Eigen::Vector2d& pixel2,
            double sqrt_info)
      : camera_(camera), point_(point1), pixel_(pixel2), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const double inv_s = std::exp(-parameters[0][7]);
    const Eigen::Vector3d p = inv_s * (q.conjugate() * (point_ - t));
    if (!optim_internal::InFrontOfCamera(p)) return false;
    ProjectionResidual(camera_, p, pixel_, sqrt_info_, residuals);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      const Eigen::Matrix<double, 2, 3> a = ProjectionJacobian(camera_, p, sqrt_info_);
      Eigen::Map<RowMajor2x8> j(jacobians[0]);
      j.block<2, 3>(0, 0) = -a;
      j.block<2, 3>(0, 3) = a * SkewSymmetric(p);
      j.block<2, 1>(0, 6) = -a * p;
      j.col(7).setZero();
    }
    return true;
  }

 private:
  PinholeCamera camera_;
  Eigen::Vector3d point_;
  Eigen::Vector2d pixel_;
  double sqrt_info_;
};

// Both whitened squared errors of a match under S; false when a point falls behind a camera.
bool MatchChi2(const Sim3RefinementProblem& problem, const Sim3Match& m, const Sim3d& s, double* chi2_1,
               double* chi2_2) {
  const Eigen::Vector3d p1 = s * m.point2;
  const Eigen::Vector3d p2 = s.Inverse() * m.point1;
  if (!optim_internal::InFrontOfCamera(p1) || !optim_internal::InFrontOfCamera(p2)) return false;
  double e[2];
  ProjectionResidual(problem.camera1, p1, m.pixel1, std::sqrt(m.inv_sigma2_1), e);
  *chi2_1 = e[0] * e[0] + e[1] * e[1];
  ProjectionResidual(problem.camera2, p2, m.pixel2, std::sqrt(m.inv_sigma2_2), e);
  *chi2_2 = e[0] * e[0] + e[1] * e[1];
  return true;
}

bool IsInlier(const Sim3RefinementProblem& problem, const Sim3Match& m, const Sim3d& s, double threshold) {
  double c1 = 0, c2 = 0;
  return MatchChi2(problem, m, s, &c1, &c2) && c1 <= threshold && c2 <= threshold;
}

}  // namespace

ceres::CostFunction* optim_internal::NewSim3ReprojectionCost(const PinholeCamera& camera,
                                                             const Eigen::Vector3d& point,
                                                             const Eigen::Vector2d& pixel, double sqrt_info,
                                                             bool into_camera1) {
  if (into_camera1) return new Into1Cost(camera, point, pixel, sqrt_info);
  return new Into2Cost(camera, point, pixel, sqrt_info);
}

Sim3RefinementResult OptimizeSim3(const Sim3RefinementProblem& problem,
                                  const Sim3d& initial_camera1_from_camera2, double chi2_threshold,
                                  bool fix_scale, const Sim3RefinementOptions& options) {
  options.Check();
  Require(std::isfinite(chi2_threshold) && chi2_threshold > 0,
          "sim3 refinement: chi2_threshold must be positive");
  optim_internal::RequirePinhole(problem.camera1, "sim3 refinement (camera1)");
  optim_internal::RequirePinhole(problem.camera2, "sim3 refinement (camera2)");
  const Sim3d& initial = initial_camera1_from_camera2;
  Require(std::isfinite(initial.scale) && initial.scale > 0 && initial.rotation.coeffs().allFinite() &&
              initial.translation.allFinite(),
          "sim3 refinement: the initial transform must be finite with a positive scale");
  for (size_t i = 0; i < problem.matches.size(); ++i) {
    const Sim3Match& m = problem.matches[i];
    const bool ok = m.point1.allFinite() && m.point2.allFinite() && m.pixel1.allFinite() &&
                    m.pixel2.allFinite() && std::isfinite(m.inv_sigma2_1) && m.inv_sigma2_1 > 0 &&
                    std::isfinite(m.inv_sigma2_2) && m.inv_sigma2_2 > 0;
    if (!ok) {
      throw InvalidArgument("sim3 refinement: match " + std::to_string(i) +
                            " has a non-finite value or inv_sigma2 <= 0");
    }
  }

  Sim3RefinementResult result;
  result.camera1_from_camera2 = initial;
  const size_t n = problem.matches.size();
  result.inliers.assign(n, false);
  if (n == 0) return result;

  double x[kSim3Size];
  optim_internal::PackSim3(initial, x);
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = true;
  ceres::Problem ceres_problem(problem_options);
  optim_internal::Sim3RightManifold manifold(fix_scale);
  ceres::HuberLoss huber(std::sqrt(chi2_threshold));
  ceres_problem.AddParameterBlock(x, kSim3Size, &manifold);
  std::vector<std::pair<ceres::ResidualBlockId, ceres::ResidualBlockId>> ids(n, {nullptr, nullptr});
  for (size_t i = 0; i < n; ++i) {
    const Sim3Match& m = problem.matches[i];
    double c1 = 0, c2 = 0;
    if (!MatchChi2(problem, m, initial, &c1, &c2)) continue;  // behind a camera: an outlier from the start
    ids[i].first = ceres_problem.AddResidualBlock(
        new Into1Cost(problem.camera1, m.point2, m.pixel1, std::sqrt(m.inv_sigma2_1)), &huber, x);
    ids[i].second = ceres_problem.AddResidualBlock(
        new Into2Cost(problem.camera2, m.point1, m.pixel2, std::sqrt(m.inv_sigma2_2)), &huber, x);
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.logging_type = ceres::SILENT;
  solver_options.num_threads = 1;
  auto solve = [&](int iterations) {
    if (ceres_problem.NumResidualBlocks() == 0) return;
    solver_options.max_num_iterations = iterations;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &ceres_problem, &summary);
  };

  solve(options.iterations);
  int dropped = 0;
  Sim3d current = optim_internal::UnpackSim3(x);
  for (size_t i = 0; i < n; ++i) {
    if (ids[i].first == nullptr) continue;
    if (!IsInlier(problem, problem.matches[i], current, chi2_threshold)) {
      ceres_problem.RemoveResidualBlock(ids[i].first);
      ceres_problem.RemoveResidualBlock(ids[i].second);
      ids[i] = {nullptr, nullptr};
      ++dropped;
    }
  }
  solve(dropped > 0 ? options.refine_iterations : options.iterations);
  current = optim_internal::UnpackSim3(x);

  result.camera1_from_camera2 = current;
  // Every match is judged by the final transform: one dropped after a first pass that had not yet converged
  // counts again when it fits.
  for (size_t i = 0; i < n; ++i) {
    const bool in = IsInlier(problem, problem.matches[i], current, chi2_threshold);
    result.inliers[i] = in;
    result.num_inliers += in ? 1 : 0;
  }
  return result;
}

}  // namespace semslam
