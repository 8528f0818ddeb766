#include "semslam/optim/pose_graph.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "semslam/core/error.h"
#include "semslam/optim/cost_functions.h"
#include "semslam/optim/internal.h"
#include "semslam/optim/manifolds.h"

namespace semslam {

void PoseGraphOptions::Check() const {
  Require(max_iterations >= 1, "pose graph: max_iterations must be >= 1");
  Require(prior_loss == RobustLoss::kHuber || prior_loss == RobustLoss::kCauchy,
          "pose graph: unknown prior_loss");
  Require(std::isfinite(prior_loss_scale) && prior_loss_scale > 0,
          "pose graph: prior_loss_scale must be positive");
  Require(num_threads >= 1, "pose graph: num_threads must be >= 1");
}

namespace {

using optim_internal::kSim3Size;
using RowMajor7x8 = Eigen::Matrix<double, 7, kSim3Size, Eigen::RowMajor>;
using RowMajor3x8 = Eigen::Matrix<double, 3, kSim3Size, Eigen::RowMajor>;
using Matrix7d = Eigen::Matrix<double, 7, 7>;

struct Sim3View {
  Eigen::Map<const Eigen::Quaterniond> q;
  Eigen::Map<const Eigen::Vector3d> t;
  double log_s;
  explicit Sim3View(const double* x) : q(x), t(x + 4), log_s(x[7]) {}
};

bool FiniteSim3(const Sim3d& s) {
  return std::isfinite(s.scale) && s.scale > 0 && s.rotation.coeffs().allFinite() &&
         s.translation.allFinite();
}

// Residual sqrt(w) [t_E; Log(R_E); log s_E] of E = M^-1 * A^-1 * B, where A = world_from_a, B = world_from_b
// and M the measured a_from_b; Jacobians for right perturbations (Sim3RightManifold) of A and B.
class RelativeSim3Cost final : public ceres::SizedCostFunction<7, kSim3Size, kSim3Size> {
 public:
  RelativeSim3Cost(const Sim3d& a_from_b, const Matrix7d& sqrt_information)
      : rm_t_(a_from_b.rotation.conjugate().toRotationMatrix()),
        tm_(a_from_b.translation),
        inv_sm_(1.0 / a_from_b.scale),
        log_sm_(std::log(a_from_b.scale)),
        sqrt_info_(sqrt_information),
        diagonal_(sqrt_information.isDiagonal(0.0)) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Sim3View a(parameters[0]), b(parameters[1]);
    const Eigen::Matrix3d ra_t = a.q.toRotationMatrix().transpose();
    const Eigen::Matrix3d rb = b.q.toRotationMatrix();
    const Eigen::Vector3d t_ab = std::exp(-a.log_s) * (ra_t * (b.t - a.t));
    const Eigen::Matrix3d r_e = rm_t_ * ra_t * rb;
    const Eigen::Vector3d t_e = inv_sm_ * (rm_t_ * (t_ab - tm_));
    const double log_se = b.log_s - a.log_s - log_sm_;
    const Eigen::Vector3d theta = QuaternionLog(Eigen::Quaterniond(r_e));
    Eigen::Map<Eigen::Matrix<double, 7, 1>> r(residuals);
    r.head<3>() = t_e;
    r.segment<3>(3) = theta;
    r(6) = log_se;
    Whiten(r);
    if (jacobians == nullptr) return true;
    if (jacobians[0] != nullptr) {
      Eigen::Map<RowMajor7x8> j(jacobians[0]);
      j.setZero();
      j.block<3, 3>(0, 0) = -inv_sm_ * rm_t_;
      j.block<3, 3>(0, 3) = SkewSymmetric(t_e) * rm_t_ + inv_sm_ * rm_t_ * SkewSymmetric(tm_);
      j.block<3, 1>(0, 6) = -t_e - inv_sm_ * (rm_t_ * tm_);
      j.block<3, 3>(3, 3) = -optim_internal::SO3LeftJacobianInverse(theta) * rm_t_;
      j(6, 6) = -1.0;
      Whiten(j);
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<RowMajor7x8> j(jacobians[1]);
      j.setZero();
      j.block<3, 3>(0, 0) = std::exp(log_se) * r_e;  // s_E * R_E
      j.block<3, 3>(3, 3) = optim_internal::SO3RightJacobianInverse(theta);
      j(6, 6) = 1.0;
      Whiten(j);
    }
    return true;
  }

 private:
  template <typename M>
  void Whiten(M& m) const {
    if (diagonal_) {
      m = sqrt_info_.diagonal().asDiagonal() * m;
    } else {
      m = (sqrt_info_ * m).eval();
    }
  }

  Eigen::Matrix3d rm_t_;  // R_m^T
  Eigen::Vector3d tm_;
  double inv_sm_, log_sm_;
  Matrix7d sqrt_info_;
  bool diagonal_;
};

// (centre - target) / sigma, the centre being world_from_node.translation.
// (centre + R * offset - target) / sigma: the point `offset` (metres, in the node's frame, e.g. a GPS antenna
// beside a camera) of a node. Under the right perturbation S * (e^sigma, Exp(phi), rho) the centre moves by
// s R rho and the offset by -R [offset]x phi; a metric offset does not scale with the node.
class PositionPriorCost final : public ceres::SizedCostFunction<3, kSim3Size> {
 public:
  PositionPriorCost(const Eigen::Vector3d& target, double sigma, const Eigen::Vector3d& offset)
      : target_(target), inv_sigma_(1.0 / sigma), offset_(offset) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Sim3View n(parameters[0]);
    const Eigen::Matrix3d r = n.q.toRotationMatrix();
    Eigen::Map<Eigen::Vector3d>{residuals} = inv_sigma_ * (n.t + r * offset_ - target_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<RowMajor3x8> j(jacobians[0]);
      j.setZero();
      j.block<3, 3>(0, 0) = (inv_sigma_ * std::exp(n.log_s)) * r;
      j.block<3, 3>(0, 3) = -inv_sigma_ * r * SkewSymmetric(offset_);
    }
    return true;
  }

 private:
  Eigen::Vector3d target_;
  double inv_sigma_;
  Eigen::Vector3d offset_;
};

// (R * axis - target) / sigma: the direction of a node's axis. Under the right perturbation Exp(phi) the
// axis moves by -R [axis]x phi.
class DirectionPriorCost final : public ceres::SizedCostFunction<3, kSim3Size> {
 public:
  DirectionPriorCost(const Eigen::Vector3d& axis, const Eigen::Vector3d& target, double sigma)
      : axis_(axis), target_(target), inv_sigma_(1.0 / sigma) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Sim3View n(parameters[0]);
    const Eigen::Matrix3d r = n.q.toRotationMatrix();
    Eigen::Map<Eigen::Vector3d>{residuals} = inv_sigma_ * (r * axis_ - target_);
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<RowMajor3x8> j(jacobians[0]);
      j.setZero();
      j.block<3, 3>(0, 3) = -inv_sigma_ * r * SkewSymmetric(axis_);
    }
    return true;
  }

 private:
  Eigen::Vector3d axis_, target_;
  double inv_sigma_;
};

// (prior_from_graph * centre - target) / sigma, with prior_from_graph a parameter too.
class FramedPositionPriorCost final : public ceres::SizedCostFunction<3, kSim3Size, kSim3Size> {
 public:
  FramedPositionPriorCost(const Eigen::Vector3d& target, double sigma)
      : target_(target), inv_sigma_(1.0 / sigma) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Sim3View n(parameters[0]), g(parameters[1]);
    const Eigen::Matrix3d sr_g = std::exp(g.log_s) * g.q.toRotationMatrix();
    Eigen::Map<Eigen::Vector3d>{residuals} = inv_sigma_ * (sr_g * n.t + g.t - target_);
    if (jacobians == nullptr) return true;
    if (jacobians[0] != nullptr) {
      Eigen::Map<RowMajor3x8> j(jacobians[0]);
      j.setZero();
      j.block<3, 3>(0, 0) = (inv_sigma_ * std::exp(n.log_s)) * (sr_g * n.q.toRotationMatrix());
    }
    if (jacobians[1] != nullptr) {
      Eigen::Map<RowMajor3x8> j(jacobians[1]);
      j.setZero();
      j.block<3, 3>(0, 0) = inv_sigma_ * sr_g;
      j.block<3, 3>(0, 3) = -inv_sigma_ * sr_g * SkewSymmetric(n.t);
      j.block<3, 1>(0, 6) = inv_sigma_ * (sr_g * n.t);
    }
    return true;
  }

 private:
  Eigen::Vector3d target_;
  double inv_sigma_;
};

}  // namespace

ceres::CostFunction* optim_internal::NewRelativeSim3Cost(
    const Sim3d& a_from_b, const Eigen::Matrix<double, 7, 7>& sqrt_information) {
  return new RelativeSim3Cost(a_from_b, sqrt_information);
}

ceres::CostFunction* optim_internal::NewDirectionPriorCost(const Eigen::Vector3d& axis,
                                                           const Eigen::Vector3d& target, double sigma) {
  return new DirectionPriorCost(axis, target, sigma);
}

ceres::CostFunction* optim_internal::NewPositionPriorCost(const Eigen::Vector3d& target, double sigma,
                                                          bool framed, const Eigen::Vector3d& offset) {
  if (framed) return new FramedPositionPriorCost(target, sigma);
  return new PositionPriorCost(target, sigma, offset);
}

int PoseGraph::AddNode(const Sim3d& world_from_node, bool fixed) {
  Require(FiniteSim3(world_from_node), "pose graph: node pose must be finite with a positive scale");
  nodes_.push_back({world_from_node, fixed});
  return static_cast<int>(nodes_.size()) - 1;
}

void PoseGraph::CheckNode(int index, const char* who) const {
  Require(index >= 0 && index < num_nodes(),
          std::string("pose graph: ") + who + ": node " + std::to_string(index) + " does not exist");
}

void PoseGraph::AddRelativeEdge(int a, int b, const Sim3d& a_from_b, double weight) {
  CheckNode(a, "AddRelativeEdge");
  CheckNode(b, "AddRelativeEdge");
  Require(a != b, "pose graph: AddRelativeEdge: an edge needs two different nodes");
  Require(FiniteSim3(a_from_b),
          "pose graph: AddRelativeEdge: measurement must be finite with a positive scale");
  Require(std::isfinite(weight) && weight > 0, "pose graph: AddRelativeEdge: weight must be positive");
  edges_.push_back({a, b, a_from_b, std::sqrt(weight) * Eigen::Matrix<double, 7, 7>::Identity()});
}

void PoseGraph::AddRelativeEdge(int a, int b, const Sim3d& a_from_b,
                                const Eigen::Matrix<double, 7, 7>& information) {
  CheckNode(a, "AddRelativeEdge");
  CheckNode(b, "AddRelativeEdge");
  Require(a != b, "pose graph: AddRelativeEdge: an edge needs two different nodes");
  Require(FiniteSim3(a_from_b),
          "pose graph: AddRelativeEdge: measurement must be finite with a positive scale");
  Require(information.allFinite() && information.isApprox(information.transpose(), 1e-9),
          "pose graph: AddRelativeEdge: information must be finite and symmetric");
  const Eigen::LLT<Eigen::Matrix<double, 7, 7>> llt(information);
  Require(llt.info() == Eigen::Success, "pose graph: AddRelativeEdge: information must be positive definite");
  edges_.push_back({a, b, a_from_b, llt.matrixU()});
}

Eigen::Matrix<double, 7, 7> PoseGraph::EdgeInformation(double sigma_translation, double sigma_rotation,
                                                       double sigma_log_scale) {
  Require(std::isfinite(sigma_translation) && sigma_translation > 0 && std::isfinite(sigma_rotation) &&
              sigma_rotation > 0 && std::isfinite(sigma_log_scale) && sigma_log_scale > 0,
          "pose graph: EdgeInformation: sigmas must be positive");
  Eigen::Matrix<double, 7, 1> d;
  d << Eigen::Vector3d::Constant(1.0 / (sigma_translation * sigma_translation)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rotation * sigma_rotation)),
      1.0 / (sigma_log_scale * sigma_log_scale);
  return d.asDiagonal();
}

int PoseGraph::AddPositionPrior(int node, const Eigen::Vector3d& target_position, double sigma_m, bool robust,
                                const Eigen::Vector3d& offset_m) {
  CheckNode(node, "AddPositionPrior");
  Require(target_position.allFinite(), "pose graph: AddPositionPrior: target must be finite");
  Require(std::isfinite(sigma_m) && sigma_m > 0, "pose graph: AddPositionPrior: sigma_m must be positive");
  Require(offset_m.allFinite(), "pose graph: AddPositionPrior: offset must be finite");
  priors_.push_back({node, target_position, sigma_m, robust, offset_m});
  return static_cast<int>(priors_.size()) - 1;
}

void PoseGraph::AddDirectionPrior(int node, const Eigen::Vector3d& axis_in_node,
                                  const Eigen::Vector3d& target_direction, double sigma_rad) {
  CheckNode(node, "AddDirectionPrior");
  Require(axis_in_node.allFinite() && target_direction.allFinite() && axis_in_node.norm() > 0 &&
              target_direction.norm() > 0,
          "pose graph: AddDirectionPrior: axis and target must be finite and non-zero");
  Require(std::isfinite(sigma_rad) && sigma_rad > 0,
          "pose graph: AddDirectionPrior: sigma_rad must be positive");
  direction_priors_.push_back({node, axis_in_node.normalized(), target_direction.normalized(), sigma_rad});
}

void PoseGraph::EstimatePriorFrame(const Sim3d& initial_prior_from_graph, bool fix_scale) {
  Require(FiniteSim3(initial_prior_from_graph), "pose graph: EstimatePriorFrame: transform must be finite");
  estimate_prior_frame_ = true;
  prior_frame_fix_scale_ = fix_scale;
  prior_from_graph_ = initial_prior_from_graph;
}

const Sim3d& PoseGraph::world_from_node(int index) const {
  CheckNode(index, "world_from_node");
  return nodes_[static_cast<size_t>(index)].world_from_node;
}

Eigen::Vector3d PoseGraph::PriorError(int index) const {
  Require(index >= 0 && index < num_priors(), "pose graph: PriorError: no such prior");
  const Prior& p = priors_[static_cast<size_t>(index)];
  const Sim3d& node = nodes_[static_cast<size_t>(p.node)].world_from_node;
  const Eigen::Vector3d point = node.translation + node.rotation * p.offset;
  return (estimate_prior_frame_ ? prior_from_graph_ * point : point) - p.target;
}

PoseGraphSummary PoseGraph::Optimize(const PoseGraphOptions& options) {
  options.Check();
  bool any_fixed = false;
  for (const Node& n : nodes_) any_fixed = any_fixed || n.fixed;
  Require(any_fixed || !priors_.empty(),
          "pose graph: Optimize: fix a node or add position priors (the gauge)");
  Require(!estimate_prior_frame_ || any_fixed,
          "pose graph: Optimize: estimating the prior frame needs a fixed node (the gauge)");
  Require(!estimate_prior_frame_ ||
              std::all_of(priors_.begin(), priors_.end(), [](const Prior& p) { return p.offset.isZero(); }),
          "pose graph: Optimize: priors with an offset are not supported in an estimated prior frame");
  PoseGraphSummary out;
  if (edges_.empty() && priors_.empty() && direction_priors_.empty()) return out;

  std::vector<double> params(nodes_.size() * kSim3Size);
  for (size_t i = 0; i < nodes_.size(); ++i)
    optim_internal::PackSim3(nodes_[i].world_from_node, &params[i * kSim3Size]);
  double frame[kSim3Size];
  optim_internal::PackSim3(prior_from_graph_, frame);

  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  optim_internal::Sim3RightManifold node_manifold(options.fix_scale);
  optim_internal::Sim3RightManifold frame_manifold(prior_frame_fix_scale_);
  for (size_t i = 0; i < nodes_.size(); ++i) {
    problem.AddParameterBlock(&params[i * kSim3Size], kSim3Size, &node_manifold);
    if (nodes_[i].fixed) problem.SetParameterBlockConstant(&params[i * kSim3Size]);
  }
  for (const Edge& e : edges_) {
    problem.AddResidualBlock(new RelativeSim3Cost(e.a_from_b, e.sqrt_information), nullptr,
                             &params[static_cast<size_t>(e.a) * kSim3Size],
                             &params[static_cast<size_t>(e.b) * kSim3Size]);
  }
  ceres::LossFunctionWrapper prior_loss(nullptr, ceres::TAKE_OWNERSHIP);
  const bool warm_start = options.prior_loss == RobustLoss::kCauchy;
  bool any_robust = false;
  if (estimate_prior_frame_) problem.AddParameterBlock(frame, kSim3Size, &frame_manifold);
  for (const Prior& p : priors_) {
    double* node = &params[static_cast<size_t>(p.node) * kSim3Size];
    ceres::LossFunction* loss = p.robust ? &prior_loss : nullptr;
    any_robust = any_robust || p.robust;
    if (estimate_prior_frame_) {
      problem.AddResidualBlock(new FramedPositionPriorCost(p.target, p.sigma), loss, node, frame);
    } else {
      problem.AddResidualBlock(new PositionPriorCost(p.target, p.sigma, p.offset), loss, node);
    }
  }
  for (const DirectionPrior& p : direction_priors_) {
    problem.AddResidualBlock(new DirectionPriorCost(p.axis, p.target, p.sigma), nullptr,
                             &params[static_cast<size_t>(p.node) * kSim3Size]);
  }

  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.logging_type = ceres::SILENT;
  solver_options.num_threads = options.num_threads;
  auto solve = [&](ceres::LossFunction* loss, bool first) {
    prior_loss.Reset(loss, ceres::TAKE_OWNERSHIP);
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);
    out.iterations += summary.num_successful_steps + summary.num_unsuccessful_steps;
    if (first) out.initial_cost = summary.initial_cost;
    out.final_cost = summary.final_cost;
    out.converged = summary.termination_type == ceres::CONVERGENCE;
  };
  if (any_robust && warm_start) {
    solve(new ceres::HuberLoss(options.prior_loss_scale), true);
    solve(new ceres::CauchyLoss(options.prior_loss_scale), false);
  } else if (options.prior_loss == RobustLoss::kHuber) {
    solve(new ceres::HuberLoss(options.prior_loss_scale), true);
  } else {
    solve(new ceres::CauchyLoss(options.prior_loss_scale), true);
  }

  for (size_t i = 0; i < nodes_.size(); ++i) {
    if (!nodes_[i].fixed) nodes_[i].world_from_node = optim_internal::UnpackSim3(&params[i * kSim3Size]);
  }
  if (estimate_prior_frame_) prior_from_graph_ = optim_internal::UnpackSim3(frame);
  return out;
}

}  // namespace semslam
