#pragma once
// Pose graph over Sim(3) nodes (Strasdat et al. 2010), ORB-SLAM's essential-graph optimization after a loop
// closure (Mur-Artal et al. 2015), and, beyond it, absolute position priors (GPS fixes, paper §III-C) with a
// robust loss, so that monocular scale drift is corrected along the trajectory and outlier fixes are
// rejected.
//
// Nodes are world_from_node similarities; with PoseGraphOptions::fix_scale they keep their scale (SE(3):
// stereo maps). Edges constrain node_a_from_node_b = world_from_a^-1 * world_from_b. Position priors pull a
// node's centre (world_from_node.translation) towards a target, either in the graph's own frame (the caller
// pre-aligns the targets, e.g. with AlignMapToGps) or in a prior frame (e.g. ENU) whose transform
// prior_from_graph is estimated jointly (EstimatePriorFrame).
//
// Weighting: ORB-SLAM's essential graph gives every edge identity information, which is fine when only
// relative constraints compete; with metric position priors the edges need their real precision
// (AddRelativeEdge with an information matrix), or the graph bends freely towards any fix, outliers included.

#include <vector>

#include "semslam/geometry/sim3.h"

namespace semslam {

enum class RobustLoss {
  kHuber,
  kCauchy,
};

struct PoseGraphOptions {
  bool fix_scale = false;  // nodes keep their scale (6 DoF each)
  int max_iterations = 20;
  // Loss of the robust position priors, on the residual in units of its sigma: quadratic up to
  // `prior_loss_scale` sigmas. With kCauchy (which rejects gross outliers but is not convex), a first solve
  // under the Huber loss of the same scale brings the graph near the inliers before the Cauchy solve.
  RobustLoss prior_loss = RobustLoss::kCauchy;
  double prior_loss_scale = 2.0;
  int num_threads = 1;

  void Check() const;  // throws InvalidArgument
};

struct PoseGraphSummary {
  int iterations = 0;
  double initial_cost = 0.0;  // Ceres cost 0.5 * sum of (robustified) squared residuals
  double final_cost = 0.0;
  bool converged = false;
};

class PoseGraph {
 public:
  // Returns the node's index. Fixed nodes do not move (fix at least one unless priors anchor the graph).
  int AddNode(const Sim3d& world_from_node, bool fixed);
  // Relative constraint `a_from_b` = world_from_a^-1 * world_from_b (as measured), with information
  // weight * I on the residual [translation (in a's units); rotation vector; log scale] of
  // a_from_b^-1 * world_from_a^-1 * world_from_b.
  void AddRelativeEdge(int a, int b, const Sim3d& a_from_b, double weight = 1.0);
  // The same with a full information matrix (symmetric positive definite) on that residual. Needed as soon
  // as position priors are in the graph: their metric sigmas only balance against edges of realistic
  // precision (see EdgeInformation), not against ORB-SLAM's identity information.
  void AddRelativeEdge(int a, int b, const Sim3d& a_from_b, const Eigen::Matrix<double, 7, 7>& information);
  // Diagonal information of an edge from the standard deviations of its translation (in a's units),
  // rotation (rad) and log scale.
  static Eigen::Matrix<double, 7, 7> EdgeInformation(double sigma_translation, double sigma_rotation,
                                                     double sigma_log_scale);
  // Absolute constraint on the centre of `node`: target_position in the graph's frame (or the prior frame,
  // see EstimatePriorFrame), isotropic standard deviation sigma_m; robust: PoseGraphOptions::prior_loss.
  // With `offset_m`, on the point that far from the centre along the node's axes, in metres (a GPS antenna
  // beside a camera: world_from_node.translation + world_from_node.rotation * offset_m); the graph's frame is
  // then metric (not with EstimatePriorFrame). Returns the prior's index.
  int AddPositionPrior(int node, const Eigen::Vector3d& target_position, double sigma_m, bool robust = true,
                       const Eigen::Vector3d& offset_m = Eigen::Vector3d::Zero());
  // Position priors are then in a frame of their own: target = prior_from_graph * centre, with
  // prior_from_graph (e.g. enu_from_world) optimized jointly from this initial guess (e.g. the closed-form
  // alignment of the same pairs), with or without its scale. Needs at least one fixed node (the priors then
  // correct the shape of the graph, the prior frame its placement). The split between prior_from_graph and
  // the nodes is only as firm as the edges at the fixed node(s); the composition prior_from_graph *
  // world_from_node is what the priors determine.
  void EstimatePriorFrame(const Sim3d& initial_prior_from_graph, bool fix_scale);
  // Absolute constraint on the direction of a node's axis (e.g. a camera's down axis): world_from_node's
  // rotation * axis_in_node towards target_direction (unit vectors), standard deviation sigma_rad, quadratic.
  // Holds a rotation the other constraints leave free (the roll about a straight drive's GPS line).
  void AddDirectionPrior(int node, const Eigen::Vector3d& axis_in_node,
                         const Eigen::Vector3d& target_direction, double sigma_rad);

  // Throws InvalidArgument on bad options or a graph without any anchor (no fixed node and no prior).
  PoseGraphSummary Optimize(const PoseGraphOptions& options = {});

  int num_nodes() const { return static_cast<int>(nodes_.size()); }
  int num_edges() const { return static_cast<int>(edges_.size()); }
  int num_priors() const { return static_cast<int>(priors_.size()); }
  const Sim3d& world_from_node(int index) const;
  const Sim3d& prior_from_graph() const { return prior_from_graph_; }
  // prior_from_graph * (centre + offset) - target, in metres, of prior `index` (after Optimize: its
  // residual).
  Eigen::Vector3d PriorError(int index) const;

 private:
  struct Node {
    Sim3d world_from_node;
    bool fixed = false;
  };
  struct Edge {
    int a = 0, b = 0;
    Sim3d a_from_b;
    Eigen::Matrix<double, 7, 7> sqrt_information;  // upper triangular, U^T U = information
  };
  struct Prior {
    int node = 0;
    Eigen::Vector3d target = Eigen::Vector3d::Zero();
    double sigma = 1.0;
    bool robust = true;
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  };

  struct DirectionPrior {
    int node = 0;
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ(), target = Eigen::Vector3d::UnitZ();
    double sigma = 1.0;
  };

  void CheckNode(int index, const char* who) const;

  std::vector<Node> nodes_;
  std::vector<Edge> edges_;
  std::vector<Prior> priors_;
  std::vector<DirectionPrior> direction_priors_;
  bool estimate_prior_frame_ = false;
  bool prior_frame_fix_scale_ = false;
  Sim3d prior_from_graph_;
};

}  // namespace semslam
