#include "semslam/geometry/pnp.h"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/geometry/alignment.h"
#include "semslam/geometry/ransac.h"

namespace semslam {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Polynomials as coefficient vectors in ascending powers.
using Polynomial = std::vector<double>;

Polynomial Multiply(const Polynomial& a, const Polynomial& b) {
  Polynomial c(a.size() + b.size() - 1, 0.0);
  for (size_t i = 0; i < a.size(); ++i) {
    for (size_t j = 0; j < b.size(); ++j) c[i + j] += a[i] * b[j];
  }
  return c;
}

Polynomial Add(const Polynomial& a, const Polynomial& b, double b_factor = 1.0) {
  Polynomial c(std::max(a.size(), b.size()), 0.0);
  for (size_t i = 0; i < a.size(); ++i) c[i] += a[i];
  for (size_t i = 0; i < b.size(); ++i) c[i] += b_factor * b[i];
  return c;
}

double Evaluate(const Polynomial& p, double x) {
  double value = 0.0;
  for (size_t i = p.size(); i-- > 0;) value = value * x + p[i];
  return value;
}

// Real roots (eigenvalues of the companion matrix with a small imaginary part, polished by Newton steps).
std::vector<double> RealRoots(Polynomial p) {
  double scale = 0.0;
  for (const double c : p) scale = std::max(scale, std::abs(c));
  if (!(scale > 0) || !std::isfinite(scale)) return {};
  while (p.size() > 1 && std::abs(p.back()) <= 1e-12 * scale) p.pop_back();
  const int degree = static_cast<int>(p.size()) - 1;
  if (degree < 1) return {};
  Eigen::MatrixXd companion = Eigen::MatrixXd::Zero(degree, degree);
  for (int i = 0; i < degree; ++i) companion(0, i) = -p[static_cast<size_t>(degree - 1 - i)] / p.back();
  for (int i = 1; i < degree; ++i) companion(i, i - 1) = 1.0;
  const Eigen::EigenSolver<Eigen::MatrixXd> solver(companion, /*computeEigenvectors=*/false);
  if (solver.info() != Eigen::Success) return {};
  Polynomial derivative(p.size() - 1);
  for (size_t i = 1; i < p.size(); ++i) derivative[i - 1] = static_cast<double>(i) * p[i];
  std::vector<double> roots;
  for (int i = 0; i < degree; ++i) {
    const std::complex<double> z = solver.eigenvalues()(i);
    if (std::abs(z.imag()) > 1e-3 * std::max(1.0, std::abs(z.real()))) continue;
    double x = z.real();
    for (int k = 0; k < 3; ++k) {
      const double d = Evaluate(derivative, x);
      if (!(std::abs(d) > 0)) break;
      const double step = Evaluate(p, x) / d;
      if (!std::isfinite(step)) break;
      x -= step;
    }
    if (std::isfinite(x)) roots.push_back(x);
  }
  return roots;
}

struct LinearSystem {
  Eigen::Matrix<double, 6, 6> hessian = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> gradient = Eigen::Matrix<double, 6, 1>::Zero();
  double cost = 0.0;
};

// Normal equations of the normalized-plane residuals under a left perturbation Exp([rho; phi]) * T.
// A point behind the camera adds a fixed penalty to the cost and nothing to the system.
LinearSystem BuildSystem(const Rigid3d& camera_from_world, const Points3d& world_points,
                         const Points3d& bearings, const std::vector<bool>& use, bool with_jacobians) {
  constexpr double kBehindPenalty = 1.0;
  LinearSystem system;
  for (size_t i = 0; i < world_points.size(); ++i) {
    if (!use.empty() && !use[i]) continue;
    const Eigen::Vector3d& b = bearings[i];
    if (!(b.z() > 0)) continue;
    const Eigen::Vector3d p = camera_from_world * world_points[i];
    if (!(p.z() > 1e-9)) {
      system.cost += kBehindPenalty;
      continue;
    }
    const double inv_z = 1.0 / p.z();
    const Eigen::Vector2d r(p.x() * inv_z - b.x() / b.z(), p.y() * inv_z - b.y() / b.z());
    system.cost += r.squaredNorm();
    if (!with_jacobians) continue;
    Eigen::Matrix<double, 2, 3> d_projection;
    d_projection << inv_z, 0, -p.x() * inv_z * inv_z, 0, inv_z, -p.y() * inv_z * inv_z;
    Eigen::Matrix<double, 3, 6> d_point;
    d_point.leftCols<3>().setIdentity();
    d_point.rightCols<3>() = -SkewSymmetric(p);
    const Eigen::Matrix<double, 2, 6> j = d_projection * d_point;
    system.hessian.noalias() += j.transpose() * j;
    system.gradient.noalias() += j.transpose() * r;
  }
  return system;
}

}  // namespace

void PnpRansacOptions::Check() const {
  Require(std::isfinite(max_reprojection_error_px) && max_reprojection_error_px > 0,
          "pnp: max_reprojection_error_px must be positive");
  Require(std::isfinite(focal_length) && focal_length > 0, "pnp: focal_length must be set (positive)");
  Require(confidence > 0 && confidence < 1, "pnp: confidence must be in (0, 1)");
  Require(max_iterations >= 1, "pnp: max_iterations must be >= 1");
  Require(min_inliers >= 3, "pnp: min_inliers must be >= 3");
  Require(refine_iterations >= 0, "pnp: refine_iterations must be >= 0");
}

std::vector<Rigid3d> SolveP3P(const std::array<Eigen::Vector3d, 3>& world_points,
                              const std::array<Eigen::Vector3d, 3>& bearings) {
  std::vector<Rigid3d> poses;
  for (int i = 0; i < 3; ++i) {
    if (!world_points[i].allFinite() || !bearings[i].allFinite() || !(bearings[i].norm() > 0)) return poses;
  }
  const Eigen::Vector3d& p1 = world_points[0];
  const Eigen::Vector3d& p2 = world_points[1];
  const Eigen::Vector3d& p3 = world_points[2];
  const double a2 = (p2 - p3).squaredNorm();
  const double b2 = (p1 - p3).squaredNorm();
  const double c2 = (p1 - p2).squaredNorm();
  const double longest2 = std::max({a2, b2, c2});
  // Collinear or coincident points leave the rotation about their line free.
  if (!(longest2 > 0) || (p2 - p1).cross(p3 - p1).squaredNorm() <= 1e-12 * longest2 * longest2) return poses;
  const Eigen::Vector3d j1 = bearings[0].normalized();
  const Eigen::Vector3d j2 = bearings[1].normalized();
  const Eigen::Vector3d j3 = bearings[2].normalized();
  const double cos_alpha = j2.dot(j3);  // angle at the centre between rays 2 and 3 (opposite side a)
  const double cos_beta = j1.dot(j3);   // rays 1, 3 (side b)
  const double cos_gamma = j1.dot(j2);  // rays 1, 2 (side c)

  // Distances s_i along the rays, s2 = u s1, s3 = v s1; the law of cosines in the three triangles gives
  //   u^2 + v^2 - 2 u v cos_alpha = (a^2 / b^2) Q(v),  1 + u^2 - 2 u cos_gamma = (c^2 / b^2) Q(v),
  // with Q(v) = 1 + v^2 - 2 v cos_beta = b^2 / s1^2. Their difference is linear in u: u = N(v) / D(v);
  // substituted into the second equation it leaves a quartic in v.
  const double k1 = a2 / b2;
  const double k2 = c2 / b2;
  const Polynomial q = {1.0, -2.0 * cos_beta, 1.0};
  const Polynomial n = Add({1.0, 0.0, -1.0}, q, k1 - k2);
  const Polynomial d = {2.0 * cos_gamma, -2.0 * cos_alpha};
  const Polynomial one_minus_k2q = Add({1.0}, q, -k2);
  const Polynomial quartic = Add(Add(Multiply(n, n), Multiply(Multiply(n, d), {-2.0 * cos_gamma})),
                                 Multiply(one_minus_k2q, Multiply(d, d)));

  const Points3d world = {p1, p2, p3};
  for (const double v : RealRoots(quartic)) {
    if (!(v > 0)) continue;
    const double dv = Evaluate(d, v);
    if (!(std::abs(dv) > 1e-12)) continue;
    const double u = Evaluate(n, v) / dv;
    const double qv = Evaluate(q, v);
    if (!(u > 0) || !(qv > 0)) continue;
    const double s1 = std::sqrt(b2 / qv);
    const Points3d in_camera = {s1 * j1, u * s1 * j2, v * s1 * j3};
    const auto camera_from_world = AlignRigid3(world, in_camera);
    if (camera_from_world) poses.push_back(*camera_from_world);
  }
  return poses;
}

double SquaredNormalizedError(const Rigid3d& camera_from_world, const Eigen::Vector3d& world_point,
                              const Eigen::Vector3d& bearing) {
  if (!(bearing.z() > 0)) return kInfinity;
  const Eigen::Vector3d p = camera_from_world * world_point;
  if (!(p.z() > 0)) return kInfinity;
  return (p.head<2>() / p.z() - bearing.head<2>() / bearing.z()).squaredNorm();
}

Rigid3d RefinePose(const Rigid3d& camera_from_world, const Points3d& world_points, const Points3d& bearings,
                   const std::vector<bool>& use, int max_iterations) {
  const size_t used =
      use.empty() ? world_points.size() : static_cast<size_t>(std::count(use.begin(), use.end(), true));
  if (used < 3 || bearings.size() != world_points.size() ||
      (!use.empty() && use.size() != world_points.size())) {
    return camera_from_world;
  }
  Rigid3d pose = camera_from_world;
  double lambda = 1e-4;
  LinearSystem system = BuildSystem(pose, world_points, bearings, use, true);
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::Matrix<double, 6, 6> damped = system.hessian;
    damped.diagonal() += lambda * system.hessian.diagonal().cwiseMax(1e-12);
    const Eigen::Matrix<double, 6, 1> step = damped.ldlt().solve(-system.gradient);
    if (!step.allFinite()) break;
    const Rigid3d candidate = Rigid3d::Exp(step) * pose;
    const LinearSystem next = BuildSystem(candidate, world_points, bearings, use, true);
    if (next.cost < system.cost) {
      pose = candidate;
      const bool converged = system.cost - next.cost <= 1e-12 * system.cost || step.norm() < 1e-12;
      system = next;
      lambda = std::max(lambda * 0.1, 1e-10);
      if (converged) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e8) break;
    }
  }
  return pose;
}

std::optional<PnpResult> SolvePnpRansac(const Points3d& world_points, const Points3d& bearings,
                                        const PnpRansacOptions& options) {
  options.Check();
  Require(world_points.size() == bearings.size(),
          fmt::format("pnp: {} world points but {} bearings", world_points.size(), bearings.size()));
  const size_t n = world_points.size();
  for (size_t i = 0; i < n; ++i) {
    Require(world_points[i].allFinite() && bearings[i].allFinite(),
            fmt::format("pnp: correspondence {} is not finite", i));
  }
  if (n < static_cast<size_t>(std::max(4, options.min_inliers))) return std::nullopt;

  const double threshold = options.max_reprojection_error_px / options.focal_length;
  const double threshold2 = threshold * threshold;
  const auto classify = [&](const Rigid3d& pose, std::vector<bool>* inliers, double* cost) {
    int count = 0;
    double total = 0.0;
    for (size_t i = 0; i < n; ++i) {
      const double e2 = SquaredNormalizedError(pose, world_points[i], bearings[i]);
      const bool inlier = e2 < threshold2;
      if (inliers != nullptr) (*inliers)[i] = inlier;
      count += inlier ? 1 : 0;
      total += inlier ? e2 : threshold2;  // MSAC: truncated quadratic
    }
    if (cost != nullptr) *cost = total;
    return count;
  };

  RansacSampler sampler(options.seed);
  std::vector<size_t> sample;
  Rigid3d best_pose;
  double best_cost = kInfinity;
  int best_count = 0;
  int needed = options.max_iterations;
  int iterations = 0;
  for (; iterations < needed; ++iterations) {
    sampler.Sample(n, 3, sample);
    const std::array<Eigen::Vector3d, 3> world = {world_points[sample[0]], world_points[sample[1]],
                                                  world_points[sample[2]]};
    const std::array<Eigen::Vector3d, 3> rays = {bearings[sample[0]], bearings[sample[1]],
                                                 bearings[sample[2]]};
    for (const Rigid3d& pose : SolveP3P(world, rays)) {
      double cost = 0.0;
      const int count = classify(pose, nullptr, &cost);
      if (cost < best_cost) {
        best_cost = cost;
        best_pose = pose;
        best_count = count;
        needed = RansacIterations(static_cast<double>(count) / static_cast<double>(n), 3, options.confidence,
                                  options.max_iterations);
      }
    }
  }
  if (best_count < std::max(4, options.min_inliers)) return std::nullopt;

  PnpResult result;
  result.iterations = iterations;
  result.inliers.assign(n, false);
  result.camera_from_world = best_pose;
  result.num_inliers = classify(best_pose, &result.inliers, nullptr);
  if (options.refine_iterations > 0) {
    // Refine on the inliers, reclassify, and again while the inlier set changes.
    for (int round = 0; round < 3; ++round) {
      const Rigid3d refined = RefinePose(result.camera_from_world, world_points, bearings, result.inliers,
                                         options.refine_iterations);
      std::vector<bool> inliers(n, false);
      const int count = classify(refined, &inliers, nullptr);
      if (count < 3) break;
      const bool changed = inliers != result.inliers;
      result.camera_from_world = refined;
      result.inliers = std::move(inliers);
      result.num_inliers = count;
      if (!changed) break;
    }
  }
  if (result.num_inliers < options.min_inliers) return std::nullopt;
  double sum = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (result.inliers[i])
      sum += SquaredNormalizedError(result.camera_from_world, world_points[i], bearings[i]);
  }
  result.rms_error_px = options.focal_length * std::sqrt(sum / result.num_inliers);
  return result;
}

}  // namespace semslam
