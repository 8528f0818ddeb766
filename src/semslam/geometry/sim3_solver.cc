#include "semslam/geometry/sim3_solver.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/geometry/alignment.h"
#include "semslam/geometry/ransac.h"

namespace semslam {
namespace {

// (error / sigma)^2 of `point` (in the camera frame) against `pixel`; infinite behind the camera.
double Chi2(const PinholeCamera& camera, const Eigen::Vector3d& point, const Eigen::Vector2d& pixel,
            double sigma2) {
  if (!(point.z() > 0)) return std::numeric_limits<double>::infinity();
  return (camera.Project(point) - pixel).squaredNorm() / sigma2;
}

// MSAC cost (each image's chi2 truncated at the threshold) and inlier count; flags into `inliers` if given.
int Evaluate(const Sim3d& camera1_from_camera2, const Sim3Correspondences& c, double chi2_threshold,
             std::vector<bool>* inliers, double* cost) {
  const Sim3d camera2_from_camera1 = camera1_from_camera2.Inverse();
  int count = 0;
  double total = 0.0;
  for (size_t i = 0; i < c.points1.size(); ++i) {
    const double chi2_in1 = Chi2(c.camera1, camera1_from_camera2 * c.points2[i], c.pixels1[i], c.sigma2_1[i]);
    const double chi2_in2 = Chi2(c.camera2, camera2_from_camera1 * c.points1[i], c.pixels2[i], c.sigma2_2[i]);
    const bool inlier = chi2_in1 < chi2_threshold && chi2_in2 < chi2_threshold;
    if (inliers != nullptr) (*inliers)[i] = inlier;
    count += inlier ? 1 : 0;
    total += std::min(chi2_in1, chi2_threshold) + std::min(chi2_in2, chi2_threshold);
  }
  if (cost != nullptr) *cost = total;
  return count;
}

std::optional<Sim3d> Align(const Points3d& src, const Points3d& tgt, bool fix_scale) {
  if (fix_scale) {
    const auto rigid = AlignRigid3(src, tgt);
    if (!rigid) return std::nullopt;
    return Sim3d(*rigid);
  }
  return AlignSim3(src, tgt);
}

// Residuals (error / sigma, 4 per match: image 1 then image 2) of the matches with use[i]; a point behind a
// camera gives a large constant residual.
Eigen::VectorXd ReprojectionResiduals(const Sim3d& camera1_from_camera2, const Sim3Correspondences& c,
                                      const std::vector<size_t>& used) {
  constexpr double kBehind = 1e3;
  const Sim3d camera2_from_camera1 = camera1_from_camera2.Inverse();
  Eigen::VectorXd r(static_cast<Eigen::Index>(4 * used.size()));
  for (size_t k = 0; k < used.size(); ++k) {
    const size_t i = used[k];
    const Eigen::Vector3d in1 = camera1_from_camera2 * c.points2[i];
    const Eigen::Vector3d in2 = camera2_from_camera1 * c.points1[i];
    const auto row = static_cast<Eigen::Index>(4 * k);
    r.segment<2>(row) =
        in1.z() > 0 ? Eigen::Vector2d((c.camera1.Project(in1) - c.pixels1[i]) / std::sqrt(c.sigma2_1[i]))
                    : Eigen::Vector2d(kBehind, kBehind);
    r.segment<2>(row + 2) =
        in2.z() > 0 ? Eigen::Vector2d((c.camera2.Project(in2) - c.pixels2[i]) / std::sqrt(c.sigma2_2[i]))
                    : Eigen::Vector2d(kBehind, kBehind);
  }
  return r;
}

// Levenberg-Marquardt on the reprojection error in both images over the inliers (numeric Jacobian; 7
// parameters, or 6 when fix_scale keeps start.scale). The step [rho; phi; log s] acts on the left: (s,
// Exp(phi), rho) * S.
Sim3d RefineOnReprojection(const Sim3d& start, const Sim3Correspondences& c, const std::vector<bool>& inliers,
                           bool fix_scale, int max_iterations) {
  std::vector<size_t> used;
  for (size_t i = 0; i < inliers.size(); ++i) {
    if (inliers[i]) used.push_back(i);
  }
  const int dof = fix_scale ? 6 : 7;
  if (static_cast<int>(used.size()) * 4 < 2 * dof) return start;
  using Vector7d = Eigen::Matrix<double, 7, 1>;
  const auto apply = [](const Sim3d& s, const Vector7d& step) {
    return Sim3d(std::exp(step(6)), QuaternionExp(step.segment<3>(3)), step.head<3>()) * s;
  };
  Sim3d state = start;
  Eigen::VectorXd r = ReprojectionResiduals(state, c, used);
  double cost = r.squaredNorm();
  double lambda = 1e-4;
  constexpr double kStep = 1e-7;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::MatrixXd jacobian(r.size(), dof);
    for (int j = 0; j < dof; ++j) {
      Vector7d delta = Vector7d::Zero();
      delta(j) = kStep;
      jacobian.col(j) = (ReprojectionResiduals(apply(state, delta), c, used) - r) / kStep;
    }
    const Eigen::MatrixXd jtj = jacobian.transpose() * jacobian;
    const Eigen::VectorXd jtr = jacobian.transpose() * r;
    bool improved = false;
    while (lambda < 1e8) {
      Eigen::MatrixXd damped = jtj;
      damped.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-12);
      const Eigen::VectorXd step = damped.ldlt().solve(-jtr);
      if (!step.allFinite()) break;
      Vector7d full = Vector7d::Zero();
      full.head(dof) = step;
      const Sim3d candidate = apply(state, full);
      const Eigen::VectorXd candidate_r = ReprojectionResiduals(candidate, c, used);
      const double candidate_cost = candidate_r.squaredNorm();
      if (candidate_cost < cost) {
        improved = cost - candidate_cost > 1e-10 * cost;
        state = candidate;
        r = candidate_r;
        cost = candidate_cost;
        lambda = std::max(lambda * 0.1, 1e-10);
        break;
      }
      lambda *= 10.0;
    }
    if (!improved) break;
  }
  if (fix_scale) state.scale = start.scale;
  return state;
}

// The scale from the 3D alignment of the inliers, each weighted by 1 / depth^2 (triangulated map points are
// uncertain mostly in depth, more so the farther they are; reprojection barely observes the scale when the
// two keyframes are close, as they are at a loop), then rotation and translation from the reprojection error.
Sim3d RefineOnInliers(const Sim3d& start, const Sim3Correspondences& c, const std::vector<bool>& inliers,
                      const Sim3RansacOptions& options) {
  Sim3d estimate = start;
  if (!options.fix_scale) {
    Points3d in2, in1;
    std::vector<double> weights;
    for (size_t i = 0; i < inliers.size(); ++i) {
      if (!inliers[i]) continue;
      in2.push_back(c.points2[i]);
      in1.push_back(c.points1[i]);
      const double depth2 =
          c.points1[i].squaredNorm() + start.scale * start.scale * c.points2[i].squaredNorm();
      weights.push_back(1.0 / std::max(depth2, 1e-12));
    }
    const auto aligned = AlignSim3(in2, in1, weights);
    if (aligned) estimate = *aligned;
  }
  return RefineOnReprojection(estimate, c, inliers, /*fix_scale=*/true, options.refine_iterations);
}

}  // namespace

void Sim3RansacOptions::Check() const {
  Require(min_inliers >= 3, "sim3 ransac: min_inliers must be >= 3");
  Require(max_iterations >= 1, "sim3 ransac: max_iterations must be >= 1");
  Require(confidence > 0 && confidence < 1, "sim3 ransac: confidence must be in (0, 1)");
  Require(std::isfinite(chi2_threshold) && chi2_threshold > 0,
          "sim3 ransac: chi2_threshold must be positive");
  Require(refine_iterations >= 0, "sim3 ransac: refine_iterations must be >= 0");
}

int ClassifySim3Inliers(const Sim3d& camera1_from_camera2, const Sim3Correspondences& correspondences,
                        double chi2_threshold, std::vector<bool>* inliers) {
  if (inliers != nullptr) inliers->assign(correspondences.points1.size(), false);
  return Evaluate(camera1_from_camera2, correspondences, chi2_threshold, inliers, nullptr);
}

std::optional<Sim3RansacResult> EstimateSim3Ransac(const Sim3Correspondences& c,
                                                   const Sim3RansacOptions& options) {
  options.Check();
  c.camera1.Check();
  c.camera2.Check();
  const size_t n = c.points1.size();
  Require(c.points2.size() == n && c.pixels1.size() == n && c.pixels2.size() == n && c.sigma2_1.size() == n &&
              c.sigma2_2.size() == n,
          fmt::format(
              "sim3 ransac: correspondence vectors differ in size ({} points1, {} points2, {} pixels1, "
              "{} pixels2, {} sigma2_1, {} sigma2_2)",
              n, c.points2.size(), c.pixels1.size(), c.pixels2.size(), c.sigma2_1.size(), c.sigma2_2.size()));
  for (size_t i = 0; i < n; ++i) {
    Require(c.points1[i].allFinite() && c.points2[i].allFinite() && c.pixels1[i].allFinite() &&
                c.pixels2[i].allFinite(),
            fmt::format("sim3 ransac: match {} is not finite", i));
    Require(std::isfinite(c.sigma2_1[i]) && c.sigma2_1[i] > 0 && std::isfinite(c.sigma2_2[i]) &&
                c.sigma2_2[i] > 0,
            fmt::format("sim3 ransac: match {} has a non-positive variance", i));
  }
  if (n < static_cast<size_t>(std::max(3, options.min_inliers))) return std::nullopt;

  RansacSampler sampler(options.seed);
  std::vector<size_t> sample;
  Points3d src(3), tgt(3);
  std::optional<Sim3d> best;
  double best_cost = std::numeric_limits<double>::infinity();
  int needed = options.max_iterations;
  int iterations = 0;
  for (; iterations < needed; ++iterations) {
    sampler.Sample(n, 3, sample);
    for (size_t k = 0; k < 3; ++k) {
      src[k] = c.points2[sample[k]];
      tgt[k] = c.points1[sample[k]];
    }
    const auto estimate = Align(src, tgt, options.fix_scale);
    if (!estimate) continue;
    double cost = 0.0;
    const int count = Evaluate(*estimate, c, options.chi2_threshold, nullptr, &cost);
    if (cost < best_cost) {
      best_cost = cost;
      best = estimate;
      needed = RansacIterations(static_cast<double>(count) / static_cast<double>(n), 3, options.confidence,
                                options.max_iterations);
    }
  }
  if (!best) return std::nullopt;

  Sim3RansacResult result;
  result.iterations = iterations;
  result.camera1_from_camera2 = *best;
  result.num_inliers = ClassifySim3Inliers(*best, c, options.chi2_threshold, &result.inliers);
  if (options.refine_iterations > 0) {
    for (int round = 0; round < 3 && result.num_inliers >= 3; ++round) {
      const Sim3d refit = RefineOnInliers(result.camera1_from_camera2, c, result.inliers, options);
      std::vector<bool> inliers;
      const int count = ClassifySim3Inliers(refit, c, options.chi2_threshold, &inliers);
      if (count < 3) break;
      const bool changed = inliers != result.inliers;
      result.camera1_from_camera2 = refit;
      result.inliers = std::move(inliers);
      result.num_inliers = count;
      if (!changed) break;
    }
  }
  if (result.num_inliers < options.min_inliers) return std::nullopt;
  return result;
}

double MedianDepthRatio(const Sim3d& camera1_from_camera2, const Points3d& points1, const Points3d& points2) {
  Require(!points1.empty() && points1.size() == points2.size(),
          fmt::format("median depth ratio: {} and {} points, need as many of each and at least one", points1.size(),
                      points2.size()));
  std::vector<double> ratios;
  ratios.reserve(points1.size());
  for (size_t i = 0; i < points1.size(); ++i) {
    Require(points1[i].allFinite() && points2[i].allFinite(),
            fmt::format("median depth ratio: point pair {} is not finite", i));
    const double mapped = (camera1_from_camera2 * points2[i]).norm();
    ratios.push_back(mapped > 0.0 ? points1[i].norm() / mapped : std::numeric_limits<double>::infinity());
  }
  const auto middle = ratios.begin() + static_cast<std::ptrdiff_t>(ratios.size() / 2);
  std::nth_element(ratios.begin(), middle, ratios.end());
  return *middle;
}

}  // namespace semslam
