#include "semslam/optim/bundle_adjustment.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "semslam/core/error.h"
#include "semslam/optim/cost_functions.h"
#include "semslam/optim/internal.h"
#include "semslam/optim/manifolds.h"

namespace semslam {

void BundleAdjustmentOptions::Check() const {
  Require(iterations >= 1, "bundle adjustment: iterations must be >= 1");
  Require(refine_iterations >= 1, "bundle adjustment: refine_iterations must be >= 1");
  Require(std::isfinite(chi2_mono) && chi2_mono > 0, "bundle adjustment: chi2_mono must be positive");
  Require(std::isfinite(chi2_stereo) && chi2_stereo > 0, "bundle adjustment: chi2_stereo must be positive");
  Require(num_threads >= 1, "bundle adjustment: num_threads must be >= 1");
  Require(solver == BundleAdjustmentSolver::kAuto || solver == BundleAdjustmentSolver::kDenseSchur ||
              solver == BundleAdjustmentSolver::kSparseSchur ||
              solver == BundleAdjustmentSolver::kIterativeSchur,
          "bundle adjustment: unknown solver");
}

namespace {

using optim_internal::kRigidSize;

struct Intrinsics {
  double fx, fy, cx, cy, bf;
};

// Whitened reprojection error (prediction - measurement) of a camera-frame point p (p.z() > 0).
template <int N>
inline void Residual(const Intrinsics& k, const Eigen::Vector3d& p, const Eigen::Vector2d& pixel,
                     double right_u, double sqrt_info, double* e) {
  const double iz = 1.0 / p.z();
  const double u = k.fx * p.x() * iz + k.cx;
  e[0] = sqrt_info * (u - pixel.x());
  e[1] = sqrt_info * (k.fy * p.y() * iz + k.cy - pixel.y());
  if constexpr (N == 3) e[2] = sqrt_info * (u - k.bf * iz - right_u);
}

// The Jacobian of N residuals with respect to camera_from_world in RigidLeftManifold's tangent space
// ([translation, rotation], the 7th ambient column zero), from `a`, their Jacobian with respect to the
// camera-frame point p.
template <int N>
void WritePoseJacobian(const Eigen::Matrix<double, N, 3, Eigen::RowMajor>& a, const Eigen::Vector3d& p,
                       double* jacobian) {
  Eigen::Map<Eigen::Matrix<double, N, kRigidSize, Eigen::RowMajor>> j(jacobian);
  for (int r = 0; r < N; ++r) {
    const Eigen::Vector3d row = a.row(r).transpose();
    j.template block<1, 3>(r, 0) = row.transpose();
    j.template block<1, 3>(r, 3) = p.cross(row).transpose();
    j(r, 6) = 0.0;
  }
}

// Reprojection of a world point into a camera: parameters camera_from_world [q, t] (RigidLeftManifold) and
// the point. N = 2: (u, v); N = 3: (u, v, u_right).
template <int N>
class ReprojectionCost final : public ceres::SizedCostFunction<N, kRigidSize, 3> {
 public:
  ReprojectionCost(const Intrinsics& k, const Eigen::Vector2d& pixel, double right_u, double sqrt_info)
      : k_(k), pixel_(pixel), right_u_(right_u), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const Eigen::Map<const Eigen::Vector3d> x(parameters[1]);
    const Eigen::Vector3d p = q * x + t;
    // A step that puts the point behind the camera is rejected.
    if (!optim_internal::InFrontOfCamera(p)) return false;
    Residual<N>(k_, p, pixel_, right_u_, sqrt_info_, residuals);
    if (jacobians == nullptr) return true;
    const double iz = 1.0 / p.z();
    const double s = sqrt_info_ * iz;
    Eigen::Matrix<double, N, 3, Eigen::RowMajor> a;
    a.row(0) << s * k_.fx, 0.0, -s * k_.fx * p.x() * iz;
    a.row(1) << 0.0, s * k_.fy, -s * k_.fy * p.y() * iz;
    if constexpr (N == 3) a.row(2) << s * k_.fx, 0.0, -s * (k_.fx * p.x() - k_.bf) * iz;
    if (jacobians[0] != nullptr) WritePoseJacobian<N>(a, p, jacobians[0]);
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, N, 3, Eigen::RowMajor>> j(jacobians[1]);
      j.noalias() = a * q.toRotationMatrix();
    }
    return true;
  }

 private:
  Intrinsics k_;
  Eigen::Vector2d pixel_;
  double right_u_;
  double sqrt_info_;
};

// Monocular reprojection with the intrinsics as a parameter block [f, cx, cy, k1, k2] (fy = f * aspect), the
// model of PinholeCamera::Project with radial distortion; the pose Jacobian in the tangent space of
// RigidLeftManifold, as ReprojectionCost has it.
class SelfCalibratingReprojectionCost final : public ceres::SizedCostFunction<2, kRigidSize, 3, 5> {
 public:
  SelfCalibratingReprojectionCost(const Eigen::Vector2d& pixel, double aspect, double sqrt_info)
      : pixel_(pixel), aspect_(aspect), sqrt_info_(sqrt_info) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> q(parameters[0]);
    const Eigen::Map<const Eigen::Vector3d> t(parameters[0] + 4);
    const Eigen::Map<const Eigen::Vector3d> x(parameters[1]);
    const double* k = parameters[2];
    const Eigen::Vector3d p = q * x + t;
    if (!optim_internal::InFrontOfCamera(p)) return false;
    const double iz = 1.0 / p.z();
    const double nx = p.x() * iz, ny = p.y() * iz;
    const double r2 = nx * nx + ny * ny;
    const double radial = 1.0 + k[3] * r2 + k[4] * r2 * r2;
    const double f = k[0], fy = k[0] * aspect_;
    residuals[0] = sqrt_info_ * (f * radial * nx + k[1] - pixel_.x());
    residuals[1] = sqrt_info_ * (fy * radial * ny + k[2] - pixel_.y());
    if (jacobians == nullptr) return true;
    // d(u, v) / d(nx, ny), then through n = (x / z, y / z).
    const double dradial = 2.0 * (k[3] + 2.0 * k[4] * r2);  // d radial / d r2 * 2
    Eigen::Matrix2d d_uv_d_n;
    d_uv_d_n << f * (radial + nx * nx * dradial), f * nx * ny * dradial, fy * nx * ny * dradial,
        fy * (radial + ny * ny * dradial);
    Eigen::Matrix<double, 2, 3> d_n_d_p;
    d_n_d_p << iz, 0.0, -nx * iz, 0.0, iz, -ny * iz;
    const Eigen::Matrix<double, 2, 3> a = sqrt_info_ * d_uv_d_n * d_n_d_p;
    if (jacobians[0] != nullptr) WritePoseJacobian<2>(a, p, jacobians[0]);
    if (jacobians[1] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>> j(jacobians[1]);
      j.noalias() = a * q.toRotationMatrix();
    }
    if (jacobians[2] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 2, 5, Eigen::RowMajor>> j(jacobians[2]);
      j << radial * nx, 1.0, 0.0, f * nx * r2, f * nx * r2 * r2,  //
          aspect_ * radial * ny, 0.0, 1.0, fy * ny * r2, fy * ny * r2 * r2;
      j *= sqrt_info_;
    }
    return true;
  }

 private:
  Eigen::Vector2d pixel_;
  double aspect_;
  double sqrt_info_;
};

// Weak priors at the nominal intrinsics: they decide only what the images cannot (straight driving says
// little about the focal length).
struct IntrinsicsPrior {
  double focal, cx, cy;
  double focal_sigma, cx_sigma, cy_sigma, distortion_sigma;

  template <typename T>
  bool operator()(const T* k, T* e) const {
    e[0] = (k[0] - T(focal)) / T(focal_sigma);
    e[1] = (k[1] - T(cx)) / T(cx_sigma);
    e[2] = (k[2] - T(cy)) / T(cy_sigma);
    e[3] = k[3] / T(distortion_sigma);
    e[4] = k[4] / T(distortion_sigma);
    return true;
  }
};

// Whitened squared reprojection error of an observation under `camera`; +infinity behind it. A camera with
// radial distortion is self-calibration's refined one (monocular problems only).
double ObservationChi2(const BundleAdjustmentProblem& problem, const BundleAdjustmentObservation& o,
                       const PinholeCamera& camera) {
  const Eigen::Vector3d p =
      problem.camera_from_world[static_cast<size_t>(o.pose)] * problem.points[static_cast<size_t>(o.point)];
  if (!optim_internal::InFrontOfCamera(p)) return std::numeric_limits<double>::infinity();
  if (!camera.distortion.IsZero()) return (camera.Project(p) - o.pixel).squaredNorm() * o.inv_sigma2;
  const Intrinsics k{camera.fx, camera.fy, camera.cx, camera.cy, camera.fx * problem.baseline};
  double e[3] = {0, 0, 0};
  const double sqrt_info = std::sqrt(o.inv_sigma2);
  if (o.right_u >= 0) {
    Residual<3>(k, p, o.pixel, o.right_u, sqrt_info, e);
  } else {
    Residual<2>(k, p, o.pixel, o.right_u, sqrt_info, e);
  }
  return e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
}

class AbortCallback final : public ceres::IterationCallback {
 public:
  explicit AbortCallback(std::atomic<bool>* abort) : abort_(abort) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return abort_->load(std::memory_order_relaxed) ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

 private:
  std::atomic<bool>* abort_;
};

// BundleAdjustmentPosePrior's residual from camera_from_world of a and b (quaternion, translation).
template <typename T>
void PosePriorResidual(const Eigen::Quaternion<T>& qa, const Eigen::Matrix<T, 3, 1>& ta,
                       const Eigen::Quaternion<T>& qb, const Eigen::Matrix<T, 3, 1>& tb,
                       const BundleAdjustmentPosePrior& prior, T* residual) {
  // a_from_b = a_from_world * world_from_b; error = measured^-1 * estimate.
  const Eigen::Quaternion<T> q_ab = qa * qb.conjugate();
  const Eigen::Matrix<T, 3, 1> t_ab = ta - q_ab * tb;
  const Eigen::Quaternion<T> measured_inverse = prior.a_from_b.rotation.conjugate().template cast<T>();
  Eigen::Quaternion<T> q_err = measured_inverse * q_ab;
  if (q_err.w() < T(0)) q_err.coeffs() = -q_err.coeffs();
  const Eigen::Matrix<T, 3, 1> t_err =
      measured_inverse * (t_ab - prior.a_from_b.translation.template cast<T>());
  for (int i = 0; i < 3; ++i) {
    residual[i] = t_err[i] / prior.sigma_translation;
    residual[3 + i] = T(2.0) * q_err.vec()[i] / prior.sigma_rotation;
  }
}

// The prior as a cost on two poses [q, t] in RigidLeftManifold's lifted tangent space: the Jacobians by
// dual numbers over the perturbations [rho, phi] of both poses at zero, where Exp(phi) ~ (1, phi / 2) is
// exact to first order.
class PosePriorCost final : public ceres::SizedCostFunction<6, kRigidSize, kRigidSize> {
 public:
  explicit PosePriorCost(const BundleAdjustmentPosePrior& prior) : prior_(prior) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Quaterniond> qa(parameters[0]), qb(parameters[1]);
    const Eigen::Map<const Eigen::Vector3d> ta(parameters[0] + 4), tb(parameters[1] + 4);
    if (jacobians == nullptr || (jacobians[0] == nullptr && jacobians[1] == nullptr)) {
      PosePriorResidual<double>(qa, ta, qb, tb, prior_, residuals);
      return true;
    }
    using Jet = ceres::Jet<double, 12>;
    auto perturbed = [](const Eigen::Quaterniond& q, const Eigen::Vector3d& t, int first,
                        Eigen::Quaternion<Jet>* q_out, Eigen::Matrix<Jet, 3, 1>* t_out) {
      Eigen::Matrix<Jet, 3, 1> rho, half_phi;
      for (int i = 0; i < 3; ++i) {
        rho[i] = Jet(0.0, first + i);
        half_phi[i] = Jet(0.0, first + 3 + i) * 0.5;
      }
      const Eigen::Quaternion<Jet> dq(Jet(1.0), half_phi.x(), half_phi.y(), half_phi.z());
      *q_out = dq * q.cast<Jet>();
      *t_out = dq * t.cast<Jet>() + rho;
    };
    Eigen::Quaternion<Jet> qa_jet, qb_jet;
    Eigen::Matrix<Jet, 3, 1> ta_jet, tb_jet;
    perturbed(qa, ta, 0, &qa_jet, &ta_jet);
    perturbed(qb, tb, 6, &qb_jet, &tb_jet);
    Jet r[6];
    PosePriorResidual<Jet>(qa_jet, ta_jet, qb_jet, tb_jet, prior_, r);
    for (int row = 0; row < 6; ++row) {
      residuals[row] = r[row].a;
      for (int pose = 0; pose < 2; ++pose) {
        if (jacobians[pose] == nullptr) continue;
        double* j = jacobians[pose] + row * kRigidSize;
        for (int k = 0; k < 6; ++k) j[k] = r[row].v[6 * pose + k];
        j[6] = 0.0;
      }
    }
    return true;
  }

 private:
  BundleAdjustmentPosePrior prior_;
};

void Validate(const BundleAdjustmentProblem& problem) {
  if (!problem.observations.empty()) optim_internal::RequirePinhole(problem.camera, "bundle adjustment");
  Require(std::isfinite(problem.baseline) && problem.baseline >= 0,
          "bundle adjustment: baseline must be finite and >= 0");
  Require(problem.pose_fixed.size() == problem.camera_from_world.size(),
          "bundle adjustment: pose_fixed must hold one flag per pose");
  for (size_t i = 0; i < problem.camera_from_world.size(); ++i) {
    const Rigid3d& t = problem.camera_from_world[i];
    if (!t.translation.allFinite() || !t.rotation.coeffs().allFinite()) {
      throw InvalidArgument("bundle adjustment: pose " + std::to_string(i) + " is not finite");
    }
  }
  for (size_t j = 0; j < problem.points.size(); ++j) {
    if (!problem.points[j].allFinite()) {
      throw InvalidArgument("bundle adjustment: point " + std::to_string(j) + " is not finite");
    }
  }
  const int num_poses = static_cast<int>(problem.camera_from_world.size());
  const int num_points = static_cast<int>(problem.points.size());
  for (size_t i = 0; i < problem.observations.size(); ++i) {
    const BundleAdjustmentObservation& o = problem.observations[i];
    const std::string which = "bundle adjustment: observation " + std::to_string(i);
    if (o.pose < 0 || o.pose >= num_poses || o.point < 0 || o.point >= num_points) {
      throw InvalidArgument(which + " refers to a pose or point out of range");
    }
    if (!o.pixel.allFinite() || !std::isfinite(o.right_u) || !std::isfinite(o.inv_sigma2) ||
        !(o.inv_sigma2 > 0)) {
      throw InvalidArgument(which + " has a non-finite value or inv_sigma2 <= 0");
    }
    if (o.right_u >= 0 && !(problem.baseline > 0)) {
      throw InvalidArgument(which + " is stereo (right_u >= 0) but the baseline is not positive");
    }
  }
  for (size_t i = 0; i < problem.pose_priors.size(); ++i) {
    const BundleAdjustmentPosePrior& prior = problem.pose_priors[i];
    const std::string which = "bundle adjustment: pose prior " + std::to_string(i);
    if (prior.a < 0 || prior.a >= num_poses || prior.b < 0 || prior.b >= num_poses || prior.a == prior.b) {
      throw InvalidArgument(which + " must tie two different poses of the problem");
    }
    if (!prior.a_from_b.translation.allFinite() || !prior.a_from_b.rotation.coeffs().allFinite() ||
        !std::isfinite(prior.sigma_translation) || !(prior.sigma_translation > 0) ||
        !std::isfinite(prior.sigma_rotation) || !(prior.sigma_rotation > 0)) {
      throw InvalidArgument(which + " has a non-finite value or a sigma <= 0");
    }
  }
}

ceres::LinearSolverType LinearSolver(BundleAdjustmentSolver solver, int num_free_poses) {
  switch (solver) {
    case BundleAdjustmentSolver::kDenseSchur:
      return ceres::DENSE_SCHUR;
    case BundleAdjustmentSolver::kSparseSchur:
      return ceres::SPARSE_SCHUR;
    case BundleAdjustmentSolver::kIterativeSchur:
      return ceres::ITERATIVE_SCHUR;
    case BundleAdjustmentSolver::kAuto:
      break;
  }
  return num_free_poses <= 60 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
}

double Chi2Threshold(const BundleAdjustmentObservation& o, const BundleAdjustmentOptions& options) {
  return o.right_u >= 0 ? options.chi2_stereo : options.chi2_mono;
}

}  // namespace

ceres::CostFunction* optim_internal::NewSelfCalibratingReprojectionCost(const Eigen::Vector2d& pixel,
                                                                        double aspect, double sqrt_info) {
  return new SelfCalibratingReprojectionCost(pixel, aspect, sqrt_info);
}

ceres::CostFunction* optim_internal::NewPosePriorCost(const Rigid3d& a_from_b, double sigma_translation,
                                                      double sigma_rotation) {
  return new PosePriorCost({0, 1, a_from_b, sigma_translation, sigma_rotation});
}

ceres::CostFunction* optim_internal::NewReprojectionCost(const PinholeCamera& camera, double bf,
                                                         const Eigen::Vector2d& pixel, double right_u,
                                                         double sqrt_info) {
  const Intrinsics k{camera.fx, camera.fy, camera.cx, camera.cy, bf};
  if (right_u >= 0) return new ReprojectionCost<3>(k, pixel, right_u, sqrt_info);
  return new ReprojectionCost<2>(k, pixel, right_u, sqrt_info);
}

double ReprojectionChi2(const BundleAdjustmentProblem& problem, const BundleAdjustmentObservation& o) {
  return ObservationChi2(problem, o, problem.camera);
}

BundleAdjustmentResult BundleAdjust(BundleAdjustmentProblem& problem,
                                    const BundleAdjustmentOptions& options) {
  options.Check();
  Validate(problem);
  const size_t num_obs = problem.observations.size();
  BundleAdjustmentResult result;
  result.outlier.assign(num_obs, false);
  if (num_obs == 0) return result;
  if (options.refine_intrinsics) {
    for (const BundleAdjustmentObservation& o : problem.observations) {
      Require(o.right_u < 0, "bundle adjustment: refine_intrinsics needs a monocular problem");
    }
  }

  const Intrinsics k{problem.camera.fx, problem.camera.fy, problem.camera.cx, problem.camera.cy,
                     problem.camera.fx * problem.baseline};
  std::vector<double> initial_chi2(num_obs);
  for (size_t i = 0; i < num_obs; ++i) initial_chi2[i] = ReprojectionChi2(problem, problem.observations[i]);

  // Parameters: poses packed as [q, t], points as they are.
  std::vector<double> poses(problem.camera_from_world.size() * kRigidSize);
  for (size_t i = 0; i < problem.camera_from_world.size(); ++i) {
    optim_internal::PackRigid(problem.camera_from_world[i], &poses[i * kRigidSize]);
  }
  std::vector<double> points(problem.points.size() * 3);
  for (size_t j = 0; j < problem.points.size(); ++j)
    Eigen::Map<Eigen::Vector3d>{&points[j * 3]} = problem.points[j];

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.enable_fast_removal = options.refine_without_outliers;
  ceres::Problem ceres_problem(problem_options);
  optim_internal::RigidLeftManifold manifold;
  ceres::LossFunctionWrapper loss_mono(new ceres::HuberLoss(std::sqrt(options.chi2_mono)),
                                       ceres::TAKE_OWNERSHIP);
  ceres::LossFunctionWrapper loss_stereo(new ceres::HuberLoss(std::sqrt(options.chi2_stereo)),
                                         ceres::TAKE_OWNERSHIP);

  // Self-calibration: [f, cx, cy, k1, k2].
  const double aspect = problem.camera.fy / problem.camera.fx;
  std::array<double, 5> intrinsics = {problem.camera.fx, problem.camera.cx, problem.camera.cy, 0.0, 0.0};
  PinholeCamera camera = problem.camera;  // the camera the state is scored with
  auto update_camera = [&] {
    if (!options.refine_intrinsics) return;
    camera.fx = intrinsics[0];
    camera.fy = intrinsics[0] * aspect;
    camera.cx = intrinsics[1];
    camera.cy = intrinsics[2];
    camera.distortion.k1 = intrinsics[3];
    camera.distortion.k2 = intrinsics[4];
  };
  auto chi2_now = [&](const BundleAdjustmentObservation& o) { return ObservationChi2(problem, o, camera); };

  std::vector<ceres::ResidualBlockId> residual_ids(num_obs, nullptr);
  std::vector<unsigned char> pose_used(problem.camera_from_world.size(), 0);
  std::vector<unsigned char> point_used(problem.points.size(), 0);
  for (size_t i = 0; i < num_obs; ++i) {
    const BundleAdjustmentObservation& o = problem.observations[i];
    // Behind its camera from the start: an outlier, kept out of the optimization.
    if (!std::isfinite(initial_chi2[i])) {
      result.outlier[i] = true;
      continue;
    }
    const auto pi = static_cast<size_t>(o.pose), pj = static_cast<size_t>(o.point);
    double* pose = &poses[pi * kRigidSize];
    double* point = &points[pj * 3];
    if (!pose_used[pi]) {
      ceres_problem.AddParameterBlock(pose, kRigidSize, &manifold);
      if (problem.pose_fixed[pi]) ceres_problem.SetParameterBlockConstant(pose);
      pose_used[pi] = 1;
    }
    point_used[pj] = 1;
    const double sqrt_info = std::sqrt(o.inv_sigma2);
    if (options.refine_intrinsics) {
      residual_ids[i] = ceres_problem.AddResidualBlock(
          new SelfCalibratingReprojectionCost(o.pixel, aspect, sqrt_info), &loss_mono, pose, point,
          intrinsics.data());
    } else if (o.right_u >= 0) {
      residual_ids[i] = ceres_problem.AddResidualBlock(
          new ReprojectionCost<3>(k, o.pixel, o.right_u, sqrt_info), &loss_stereo, pose, point);
    } else {
      residual_ids[i] = ceres_problem.AddResidualBlock(
          new ReprojectionCost<2>(k, o.pixel, o.right_u, sqrt_info), &loss_mono, pose, point);
    }
  }

  for (const BundleAdjustmentPosePrior& prior : problem.pose_priors) {
    for (const int i : {prior.a, prior.b}) {
      const auto pi = static_cast<size_t>(i);
      if (pose_used[pi]) continue;
      ceres_problem.AddParameterBlock(&poses[pi * kRigidSize], kRigidSize, &manifold);
      if (problem.pose_fixed[pi]) ceres_problem.SetParameterBlockConstant(&poses[pi * kRigidSize]);
      pose_used[pi] = 1;
    }
    ceres_problem.AddResidualBlock(new PosePriorCost(prior), nullptr,
                                   &poses[static_cast<size_t>(prior.a) * kRigidSize],
                                   &poses[static_cast<size_t>(prior.b) * kRigidSize]);
  }

  if (options.refine_intrinsics) {
    const PinholeCamera& c = problem.camera;
    ceres_problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<IntrinsicsPrior, 5, 5>(new IntrinsicsPrior{
            c.fx, c.cx, c.cy, 0.05 * c.fx, 0.05 * std::max(c.width, 1), 0.05 * std::max(c.height, 1), 0.1}),
        nullptr, intrinsics.data());
  }

  int num_free_poses = 0;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (size_t j = 0; j < point_used.size(); ++j) {
    if (point_used[j]) ordering->AddElementToGroup(&points[j * 3], 0);
  }
  for (size_t i = 0; i < pose_used.size(); ++i) {
    if (!pose_used[i]) continue;
    ordering->AddElementToGroup(&poses[i * kRigidSize], 1);
    num_free_poses += problem.pose_fixed[i] ? 0 : 1;
  }
  if (options.refine_intrinsics) ordering->AddElementToGroup(intrinsics.data(), 1);

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = LinearSolver(options.solver, num_free_poses);
  if (solver_options.linear_solver_type == ceres::ITERATIVE_SCHUR) {
    solver_options.preconditioner_type = ceres::SCHUR_JACOBI;
  }
  solver_options.linear_solver_ordering = ordering;
  solver_options.logging_type = ceres::SILENT;
  solver_options.num_threads = options.num_threads;
  AbortCallback abort_callback(options.abort);
  if (options.abort != nullptr) {
    solver_options.callbacks.push_back(&abort_callback);
    solver_options.update_state_every_iteration = true;  // an abort keeps the best state found so far
  }

  auto solve = [&](int iterations) {
    if (ceres_problem.NumResidualBlocks() == 0) return;
    solver_options.max_num_iterations = iterations;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &ceres_problem, &summary);
    result.iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
    if (summary.termination_type == ceres::USER_FAILURE) result.aborted = true;
  };
  auto write_back = [&] {
    for (size_t i = 0; i < problem.camera_from_world.size(); ++i) {
      if (pose_used[i] && !problem.pose_fixed[i]) {
        problem.camera_from_world[i] = optim_internal::UnpackRigid(&poses[i * kRigidSize]);
      }
    }
    for (size_t j = 0; j < problem.points.size(); ++j) {
      if (point_used[j]) problem.points[j] = Eigen::Map<const Eigen::Vector3d>(&points[j * 3]);
    }
    update_camera();
  };

  solve(options.iterations);
  write_back();
  if (options.refine_without_outliers && !result.aborted) {
    for (size_t i = 0; i < num_obs; ++i) {
      if (residual_ids[i] == nullptr) continue;
      const BundleAdjustmentObservation& o = problem.observations[i];
      if (chi2_now(o) > Chi2Threshold(o, options)) {
        result.outlier[i] = true;
        ceres_problem.RemoveResidualBlock(residual_ids[i]);
        residual_ids[i] = nullptr;
      }
    }
    loss_mono.Reset(nullptr, ceres::TAKE_OWNERSHIP);
    loss_stereo.Reset(nullptr, ceres::TAKE_OWNERSHIP);
    solve(options.refine_iterations);
    write_back();
  }

  double initial_sum = 0.0, final_sum = 0.0;
  int counted = 0;
  for (size_t i = 0; i < num_obs; ++i) {
    if (result.outlier[i]) continue;
    const BundleAdjustmentObservation& o = problem.observations[i];
    const double chi2 = chi2_now(o);
    if (chi2 > Chi2Threshold(o, options)) {  // also catches points now behind the camera (infinite chi2)
      result.outlier[i] = true;
      continue;
    }
    initial_sum += initial_chi2[i];
    final_sum += chi2;
    ++counted;
  }
  for (size_t i = 0; i < num_obs; ++i) {
    const BundleAdjustmentObservation& o = problem.observations[i];
    const double threshold = Chi2Threshold(o, options);
    result.initial_capped_chi2 += std::min(initial_chi2[i], threshold);
    result.final_capped_chi2 += std::min(chi2_now(o), threshold);
  }
  for (size_t i = 0; i < num_obs; ++i) result.num_outliers += result.outlier[i] ? 1 : 0;
  if (counted > 0) {
    result.initial_rms = std::sqrt(initial_sum / counted);
    result.final_rms = std::sqrt(final_sum / counted);
  }
  if (options.refine_intrinsics) result.refined_camera = camera;
  return result;
}

}  // namespace semslam
