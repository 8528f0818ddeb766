#include "semslam/optim/pose_optimization.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "semslam/core/error.h"
#include "semslam/optim/internal.h"
#include "semslam/optim/manifolds.h"

namespace semslam {

void PoseOptimizationOptions::Check() const {
  Require(rounds >= 1, "pose optimization: rounds must be >= 1");
  Require(iterations_per_round >= 1, "pose optimization: iterations_per_round must be >= 1");
  Require(robust_rounds >= 0, "pose optimization: robust_rounds must be >= 0");
  Require(std::isfinite(chi2_mono) && chi2_mono > 0, "pose optimization: chi2_mono must be positive");
  Require(std::isfinite(chi2_stereo) && chi2_stereo > 0, "pose optimization: chi2_stereo must be positive");
  Require(min_inliers >= 0, "pose optimization: min_inliers must be >= 0");
  Require(solver == PoseSolver::kGaussNewton || solver == PoseSolver::kCeres,
          "pose optimization: unknown solver");
}

namespace {

using optim_internal::HuberCost;
using optim_internal::HuberWeight;

// An observation as the solvers use it: whitening factor instead of inverse variance.
struct Measurement {
  Eigen::Vector3d point;
  double u, v, right_u;
  double sqrt_info;
  bool stereo;
};

struct Intrinsics {
  double fx, fy, cx, cy, bf;  // bf = fx * baseline
};

// Whitened error (prediction - measurement) of `m` seen from camera point `p` (p.z() > 0).
inline double WhitenedError(const Measurement& m, const Eigen::Vector3d& p, const Intrinsics& k, double* e) {
  const double iz = 1.0 / p.z();
  const double u = k.fx * p.x() * iz + k.cx;
  e[0] = m.sqrt_info * (u - m.u);
  e[1] = m.sqrt_info * (k.fy * p.y() * iz + k.cy - m.v);
  double e2 = e[0] * e[0] + e[1] * e[1];
  if (m.stereo) {
    e[2] = m.sqrt_info * (u - k.bf * iz - m.right_u);
    e2 += e[2] * e[2];
  }
  return e2;
}

// Scratch space reused across calls on the same thread (tracking calls this several times per frame).
struct Scratch {
  std::vector<Measurement> measurements;
  std::vector<unsigned char> active;
};

void Validate(const PoseOptimizationProblem& problem) {
  optim_internal::RequirePinhole(problem.camera, "pose optimization");
  Require(problem.camera_from_world.translation.allFinite() &&
              problem.camera_from_world.rotation.coeffs().allFinite(),
          "pose optimization: the initial pose must be finite");
  Require(std::isfinite(problem.baseline) && problem.baseline >= 0,
          "pose optimization: baseline must be finite and >= 0");
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    const PoseObservation& o = problem.observations[i];
    const bool ok = o.point.allFinite() && o.pixel.allFinite() && std::isfinite(o.right_u) &&
                    std::isfinite(o.inv_sigma2) && o.inv_sigma2 > 0;
    if (!ok) {
      throw InvalidArgument("pose optimization: observation " + std::to_string(i) +
                            " has a non-finite value or inv_sigma2 <= 0");
    }
    if (o.right_u >= 0 && !(problem.baseline > 0)) {
      throw InvalidArgument("pose optimization: observation " + std::to_string(i) +
                            " is stereo (right_u >= 0) but the baseline is not positive");
    }
  }
}

// Classifies every measurement at pose (r, t): active = in front of the camera and within the chi-square
// threshold. Returns the number of inliers.
int Classify(const std::vector<Measurement>& ms, const Eigen::Matrix3d& r, const Eigen::Vector3d& t,
             const Intrinsics& k, const PoseOptimizationOptions& options,
             std::vector<unsigned char>& active) {
  int inliers = 0;
  double e[3] = {0.0, 0.0, 0.0};
  for (size_t i = 0; i < ms.size(); ++i) {
    const Eigen::Vector3d p = r * ms[i].point + t;
    bool in = false;
    if (optim_internal::InFrontOfCamera(p)) {
      const double e2 = WhitenedError(ms[i], p, k, e);
      in = e2 <= (ms[i].stereo ? options.chi2_stereo : options.chi2_mono);
    }
    active[i] = in ? 1 : 0;
    inliers += in ? 1 : 0;
  }
  return inliers;
}

// ---------------------------------------------------------------------------------------------------------
// Hand-written Levenberg-Marquardt on the 6 pose parameters, left perturbation [rho, phi]:
// camera_from_world <- [Exp(phi) | rho] * camera_from_world, so dp/d[rho, phi] = [I, -[p]x].

class PoseLm {
 public:
  PoseLm(const std::vector<Measurement>& ms, const std::vector<unsigned char>& active, const Intrinsics& k,
         double delta2_mono, double delta2_stereo, bool robust)
      : ms_(ms),
        active_(active),
        k_(k),
        delta2_mono_(delta2_mono),
        delta2_stereo_(delta2_stereo),
        robust_(robust) {}

  // Robust cost at (r, t); behind-camera active points make the pose invalid (infinite cost).
  double Cost(const Eigen::Matrix3d& r, const Eigen::Vector3d& t) const {
    double cost = 0.0, e[3] = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < ms_.size(); ++i) {
      if (!active_[i]) continue;
      const Eigen::Vector3d p = r * ms_[i].point + t;
      if (!optim_internal::InFrontOfCamera(p)) return std::numeric_limits<double>::infinity();
      const double e2 = WhitenedError(ms_[i], p, k_, e);
      cost += robust_ ? HuberCost(e2, ms_[i].stereo ? delta2_stereo_ : delta2_mono_) : e2;
    }
    return cost;
  }

  // Cost, IRLS-weighted normal equations H and gradient g (of the Gauss-Newton model cost + 2 g'd + d'Hd).
  double Linearize(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, Eigen::Matrix6d& h,
                   Eigen::Vector6d& g) const {
    // The upper triangle of H, row by row (21 entries), and g, accumulated in plain arrays: Eigen's
    // generic outer product does not inline here and costs twice as much.
    double hu[21] = {}, gg[6] = {};
    double cost = 0.0, e[3] = {0.0, 0.0, 0.0};
    for (size_t i = 0; i < ms_.size(); ++i) {
      if (!active_[i]) continue;
      const Measurement& m = ms_[i];
      const Eigen::Vector3d p = r * m.point + t;
      if (!optim_internal::InFrontOfCamera(p)) return std::numeric_limits<double>::infinity();
      const double e2 = WhitenedError(m, p, k_, e);
      double w = 1.0;
      if (robust_) {
        const double d2 = m.stereo ? delta2_stereo_ : delta2_mono_;
        cost += HuberCost(e2, d2);
        w = HuberWeight(e2, d2);
      } else {
        cost += e2;
      }
      const double iz = 1.0 / p.z();
      const double s = m.sqrt_info * iz;
      // A row a of de/dp gives the Jacobian row [a, p x a].
      auto add_row = [&](double ax, double ay, double az, double err) {
        const double j[6] = {
            ax, ay, az, p.y() * az - p.z() * ay, p.z() * ax - p.x() * az, p.x() * ay - p.y() * ax};
        int k = 0;
        for (int u = 0; u < 6; ++u) {
          const double wj = w * j[u];
          gg[u] += wj * err;
          for (int v = u; v < 6; ++v) hu[k++] += wj * j[v];
        }
      };
      add_row(s * k_.fx, 0.0, -s * k_.fx * p.x() * iz, e[0]);
      add_row(0.0, s * k_.fy, -s * k_.fy * p.y() * iz, e[1]);
      if (m.stereo) add_row(s * k_.fx, 0.0, -s * (k_.fx * p.x() - k_.bf) * iz, e[2]);
    }
    int k = 0;
    for (int u = 0; u < 6; ++u) {
      g(u) = gg[u];
      for (int v = u; v < 6; ++v) h(u, v) = h(v, u) = hu[k++];
    }
    return cost;
  }

  // At most `iterations` Levenberg-Marquardt steps (damping update of Nielsen); stops early once a step
  // gains less than a relative 1e-7 of the cost or the model promises less than that.
  void Run(Eigen::Matrix3d& r, Eigen::Vector3d& t, int iterations) const {
    constexpr double kTolerance = 1e-7;
    Eigen::Matrix6d h;
    Eigen::Vector6d g;
    double cost = Linearize(r, t, h, g);
    if (!std::isfinite(cost)) return;
    double lambda = 1e-5 * std::max(h.diagonal().maxCoeff(), 1e-12), nu = 2.0;
    for (int it = 0; it < iterations; ++it) {
      bool accepted = false;
      for (int attempt = 0; attempt < 10 && !accepted; ++attempt) {
        Eigen::Matrix6d a = h;
        a.diagonal().array() += lambda;
        const Eigen::Vector6d delta = a.ldlt().solve(-g);
        const double predicted = delta.dot(lambda * delta - g);
        if (!delta.allFinite() || !(predicted > 0)) {
          lambda *= nu;
          nu *= 2.0;
          continue;
        }
        if (predicted <= kTolerance * cost) return;  // nothing left to gain
        const Eigen::Matrix3d dr = QuaternionExp(delta.tail<3>()).toRotationMatrix();
        const Eigen::Matrix3d r_new = dr * r;
        const Eigen::Vector3d t_new = dr * t + delta.head<3>();
        const double cost_new = Cost(r_new, t_new);
        if (cost_new < cost) {
          const double rho = (cost - cost_new) / predicted;
          lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
          nu = 2.0;
          r = Eigen::Quaterniond(r_new).normalized().toRotationMatrix();  // keep R orthonormal
          t = t_new;
          accepted = true;
          if (cost - cost_new <= kTolerance * cost) return;
        } else {
          lambda *= nu;
          nu *= 2.0;
        }
      }
      if (!accepted) return;  // no descent from here
      if (it + 1 < iterations) {
        cost = Linearize(r, t, h, g);
        if (!std::isfinite(cost)) return;
      }
    }
  }

 private:
  const std::vector<Measurement>& ms_;
  const std::vector<unsigned char>& active_;
  const Intrinsics& k_;
  double delta2_mono_, delta2_stereo_;
  bool robust_;
};

Rigid3d SolveGaussNewton(const Rigid3d& initial, const Intrinsics& k, const PoseOptimizationOptions& options,
                         Scratch& s) {
  Eigen::Matrix3d r = initial.rotation.normalized().toRotationMatrix();
  Eigen::Vector3d t = initial.translation;
  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    PoseLm lm(s.measurements, s.active, k, options.chi2_mono, options.chi2_stereo, robust);
    lm.Run(r, t, options.iterations_per_round);
    const int inliers = Classify(s.measurements, r, t, k, options, s.active);
    if (inliers < options.min_inliers) break;
  }
  return Rigid3d(r, t);
}

// ---------------------------------------------------------------------------------------------------------
// The same optimization through Ceres: one problem, one solve per round; inactive observations contribute a
// zero residual, and the Huber kernels sit in wrappers that the last rounds reset to the plain square.

class PoseCost final : public ceres::CostFunction {
 public:
  PoseCost(const Measurement& m, const Intrinsics& k, const unsigned char* active)
      : m_(m), k_(k), active_(active) {
    set_num_residuals(m.stereo ? 3 : 2);
    mutable_parameter_block_sizes()->push_back(optim_internal::kRigidSize);
  }

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const int n = num_residuals();
    double* jac = (jacobians != nullptr) ? jacobians[0] : nullptr;
    if (!*active_) {
      std::fill(residuals, residuals + n, 0.0);
      if (jac != nullptr) std::fill(jac, jac + n * optim_internal::kRigidSize, 0.0);
      return true;
    }
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const Eigen::Vector3d p = q * m_.point + t;
    if (!optim_internal::InFrontOfCamera(p)) return false;
    WhitenedError(m_, p, k_, residuals);
    if (jac != nullptr) {
      const double iz = 1.0 / p.z();
      const double s = m_.sqrt_info * iz;
      const Eigen::Vector3d rows[3] = {{s * k_.fx, 0.0, -s * k_.fx * p.x() * iz},
                                       {0.0, s * k_.fy, -s * k_.fy * p.y() * iz},
                                       {s * k_.fx, 0.0, -s * (k_.fx * p.x() - k_.bf) * iz}};
      for (int row = 0; row < n; ++row) {
        Eigen::Map<Eigen::Matrix<double, 1, 7>> out(jac + row * 7);
        out.head<3>() = rows[row].transpose();
        out.segment<3>(3) = p.cross(rows[row]).transpose();
        out(6) = 0.0;
      }
    }
    return true;
  }

 private:
  Measurement m_;
  Intrinsics k_;
  const unsigned char* active_;
};

Rigid3d SolveCeres(const Rigid3d& initial, const Intrinsics& k, const PoseOptimizationOptions& options,
                   Scratch& s) {
  double pose[optim_internal::kRigidSize];
  optim_internal::PackRigid(initial, pose);
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  optim_internal::RigidLeftManifold manifold;
  ceres::LossFunctionWrapper loss_mono(nullptr, ceres::TAKE_OWNERSHIP);
  ceres::LossFunctionWrapper loss_stereo(nullptr, ceres::TAKE_OWNERSHIP);
  problem.AddParameterBlock(pose, optim_internal::kRigidSize, &manifold);
  for (size_t i = 0; i < s.measurements.size(); ++i) {
    problem.AddResidualBlock(new PoseCost(s.measurements[i], k, &s.active[i]),
                             s.measurements[i].stereo ? &loss_stereo : &loss_mono, pose);
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.iterations_per_round;
  solver_options.logging_type = ceres::SILENT;
  solver_options.num_threads = 1;
  for (int round = 0; round < options.rounds; ++round) {
    if (round < options.robust_rounds) {
      loss_mono.Reset(new ceres::HuberLoss(std::sqrt(options.chi2_mono)), ceres::TAKE_OWNERSHIP);
      loss_stereo.Reset(new ceres::HuberLoss(std::sqrt(options.chi2_stereo)), ceres::TAKE_OWNERSHIP);
    } else {
      loss_mono.Reset(nullptr, ceres::TAKE_OWNERSHIP);
      loss_stereo.Reset(nullptr, ceres::TAKE_OWNERSHIP);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    const Rigid3d current = optim_internal::UnpackRigid(pose);
    const int inliers = Classify(s.measurements, current.rotation.toRotationMatrix(), current.translation, k,
                                 options, s.active);
    if (inliers < options.min_inliers) break;
  }
  return optim_internal::UnpackRigid(pose);
}

}  // namespace

PoseOptimizationResult OptimizePose(const PoseOptimizationProblem& problem,
                                    const PoseOptimizationOptions& options) {
  options.Check();
  Validate(problem);
  PoseOptimizationResult result;
  result.camera_from_world = problem.camera_from_world;
  const size_t n = problem.observations.size();
  result.inliers.assign(n, false);
  if (n == 0) return result;

  thread_local Scratch scratch;
  Scratch& s = scratch;
  s.measurements.resize(n);
  s.active.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const PoseObservation& o = problem.observations[i];
    s.measurements[i] = {o.point,       o.pixel.x(), o.pixel.y(), o.right_u, std::sqrt(o.inv_sigma2),
                         o.right_u >= 0};
  }
  const Intrinsics k{problem.camera.fx, problem.camera.fy, problem.camera.cx, problem.camera.cy,
                     problem.camera.fx * problem.baseline};
  // The first round starts from every observation in front of the camera.
  const Eigen::Matrix3d r0 = problem.camera_from_world.rotation.normalized().toRotationMatrix();
  for (size_t i = 0; i < n; ++i)
    s.active[i] =
        optim_internal::InFrontOfCamera(r0 * s.measurements[i].point + problem.camera_from_world.translation);

  result.camera_from_world = options.solver == PoseSolver::kCeres
                                 ? SolveCeres(problem.camera_from_world, k, options, s)
                                 : SolveGaussNewton(problem.camera_from_world, k, options, s);
  for (size_t i = 0; i < n; ++i) {
    result.inliers[i] = s.active[i] != 0;
    result.num_inliers += s.active[i] != 0 ? 1 : 0;
  }
  return result;
}

}  // namespace semslam
