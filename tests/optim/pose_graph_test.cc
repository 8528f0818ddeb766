#include "semslam/optim/pose_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "semslam/core/error.h"
#include "support/draws.h"
#include "synthetic.h"

namespace semslam {
namespace {

using testing::DrawVector3;
using testing_optim::RandomRigid;
using testing_optim::RandomVector;
using testing_optim::RotationError;

// A closed drive: N keyframes on a circle of radius 30 m (1.9 m apart) with a gentle vertical wave; camera
// z along the direction of travel, y down.
std::vector<Rigid3d> LoopTrajectory(int n) {
  std::vector<Rigid3d> world_from_camera;
  for (int i = 0; i < n; ++i) {
    const double theta = 2.0 * M_PI * i / n;
    const Eigen::Vector3d centre(30.0 * (1.0 - std::cos(theta)), 0.5 * std::sin(3.0 * theta),
                                 30.0 * std::sin(theta));
    world_from_camera.emplace_back(Eigen::Quaterniond(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY())),
                                   centre);
  }
  return world_from_camera;
}

// Monocular odometry with scale drift: the relative motion i -> i+1 is measured in the local map's units,
// which grow by `drift` per step, and believed metric-consistent (relative scale 1). Small noise on top.
struct DriftingChain {
  std::vector<Rigid3d> truth;       // world_from_camera, metric
  std::vector<double> local_scale;  // k_i: local map units per metre
  std::vector<Sim3d> odometry;      // measured i_from_(i+1)
  std::vector<Sim3d> initial;       // world_from_node chained from the odometry
};

DriftingChain MakeDriftingChain(int n, double drift, double noise, std::uint32_t seed) {
  std::mt19937 rng(seed);
  DriftingChain c;
  c.truth = LoopTrajectory(n);
  for (int i = 0; i < n; ++i) c.local_scale.push_back(std::pow(1.0 + drift, i));
  c.initial.push_back(Sim3d(c.truth[0]));
  for (int i = 0; i + 1 < n; ++i) {
    const Rigid3d rel = c.truth[static_cast<size_t>(i)].Inverse() * c.truth[static_cast<size_t>(i) + 1];
    const Rigid3d error = RandomRigid(rng, noise, noise);
    const Sim3d measured(1.0, error.rotation * rel.rotation,
                         c.local_scale[static_cast<size_t>(i)] * rel.translation + error.translation);
    c.odometry.push_back(measured);
    c.initial.push_back(c.initial.back() * measured);
  }
  return c;
}

// The similarity a_from_b that a Sim(3) loop closure measures between nodes whose maps have local scales
// k_a and k_b: node frames are (1 / k, R, centre) in the metric world.
Sim3d TrueRelative(const DriftingChain& c, int a, int b) {
  auto node = [&](int i) {
    const Rigid3d& t = c.truth[static_cast<size_t>(i)];
    return Sim3d(1.0 / c.local_scale[static_cast<size_t>(i)], t.rotation, t.translation);
  };
  return node(a).Inverse() * node(b);
}

double MaxPositionError(const PoseGraph& g, const std::vector<Rigid3d>& truth) {
  double worst = 0;
  for (int i = 0; i < g.num_nodes(); ++i) {
    worst = std::max(worst,
                     (g.world_from_node(i).translation - truth[static_cast<size_t>(i)].translation).norm());
  }
  return worst;
}

double MaxPositionError(const std::vector<Sim3d>& nodes, const std::vector<Rigid3d>& truth) {
  double worst = 0;
  for (size_t i = 0; i < nodes.size(); ++i)
    worst = std::max(worst, (nodes[i].translation - truth[i].translation).norm());
  return worst;
}

TEST(PoseGraph, ConsistentEdgesGiveTheExactPoses) {
  std::mt19937 rng(1);
  const std::vector<Rigid3d> truth = LoopTrajectory(40);
  std::vector<Sim3d> nodes;
  for (size_t i = 0; i < truth.size(); ++i)
    nodes.emplace_back(std::exp(0.1 * std::sin(0.3 * i)), truth[i].rotation, truth[i].translation);
  PoseGraph g;
  for (size_t i = 0; i < nodes.size(); ++i) {
    Sim3d perturbed = nodes[i];
    if (i > 0) {
      const Rigid3d error = RandomRigid(rng, 0.05, 0.5);
      perturbed = nodes[i] * Sim3d(std::exp(0.05), error.rotation, error.translation);
    }
    g.AddNode(perturbed, i == 0);
  }
  for (size_t i = 0; i < nodes.size(); ++i) {
    const size_t j = (i + 1) % nodes.size();
    g.AddRelativeEdge(static_cast<int>(i), static_cast<int>(j), nodes[i].Inverse() * nodes[j]);
    if (i + 5 < nodes.size())
      g.AddRelativeEdge(static_cast<int>(i), static_cast<int>(i + 5), nodes[i].Inverse() * nodes[i + 5], 2.0);
  }
  PoseGraphOptions options;
  options.max_iterations = 50;
  const PoseGraphSummary summary = g.Optimize(options);
  EXPECT_LT(summary.final_cost, 1e-12);
  for (int i = 0; i < g.num_nodes(); ++i) {
    const Sim3d& got = g.world_from_node(i);
    EXPECT_LT((got.translation - nodes[static_cast<size_t>(i)].translation).norm(), 1e-6);
    EXPECT_LT(RotationError(got.rotation, nodes[static_cast<size_t>(i)].rotation), 1e-7);
    EXPECT_NEAR(got.scale, nodes[static_cast<size_t>(i)].scale, 1e-7);
  }
  EXPECT_EQ(g.world_from_node(0).translation, nodes[0].translation);  // fixed
}

TEST(PoseGraph, LoopEdgeCorrectsMonocularScaleDrift) {
  const int n = 100;
  const DriftingChain c = MakeDriftingChain(n, 0.01, 1e-3, 2);
  const double initial_error = MaxPositionError(c.initial, c.truth);
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.AddNode(c.initial[static_cast<size_t>(i)], i == 0);
  for (int i = 0; i + 1 < n; ++i) g.AddRelativeEdge(i, i + 1, c.odometry[static_cast<size_t>(i)]);
  g.AddRelativeEdge(n - 1, 0, TrueRelative(c, n - 1, 0));
  PoseGraphOptions options;
  options.max_iterations = 50;
  g.Optimize(options);
  const double error = MaxPositionError(g, c.truth);
  // 1 % drift per step leaves the chain's end scaled 2.7x and tens of metres off; the loop brings every
  // keyframe back within 0.5 % of the 188 m loop (at worst 0.54 m over 20 seeds).
  EXPECT_GT(initial_error, 30.0);
  EXPECT_LT(error, 1.0) << "initial " << initial_error;
  // The node scales follow the local map scales (1 / k_i), up to the spread of the inconsistency.
  EXPECT_NEAR(std::log(g.world_from_node(n - 1).scale), -std::log(c.local_scale.back()), 0.05);
}

// Odometry precision for graphs with position priors: 2 cm (local units), 2 mrad, 1 % in scale per edge.
Eigen::Matrix<double, 7, 7> OdometryInformation() { return PoseGraph::EdgeInformation(0.02, 0.002, 0.05); }

TEST(PoseGraph, RobustPositionPriorsCorrectDriftAndRejectOutliers) {
  const int n = 100;
  const DriftingChain c = MakeDriftingChain(n, 0.01, 1e-3, 3);
  std::mt19937 rng(4);
  std::normal_distribution<double> gps_noise(0.0, 0.5);
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.AddNode(c.initial[static_cast<size_t>(i)], i == 0);
  for (int i = 0; i + 1 < n; ++i)
    g.AddRelativeEdge(i, i + 1, c.odometry[static_cast<size_t>(i)], OdometryInformation());
  // A fix (sigma 0.5 m) on every keyframe after the first; 5 of the 99 are 50 m off.
  std::vector<bool> bad;
  for (int i = 1; i < n; ++i) {
    Eigen::Vector3d target = c.truth[static_cast<size_t>(i)].translation + DrawVector3(gps_noise, rng);
    const bool outlier = i % 20 == 7;
    if (outlier) target += 50.0 * RandomVector(rng, 1.0).normalized();
    g.AddPositionPrior(i, target, 0.5, true);
    bad.push_back(outlier);
  }
  ASSERT_EQ(std::count(bad.begin(), bad.end(), true), 5);
  const double initial_error = MaxPositionError(g, c.truth);
  PoseGraphOptions options;
  options.max_iterations = 50;
  g.Optimize(options);
  const double error = MaxPositionError(g, c.truth);
  EXPECT_GT(initial_error, 30.0);
  EXPECT_LT(error, 1.0) << "initial " << initial_error;  // at worst 0.71 m over 20 seeds
  for (int k = 0; k < g.num_priors(); ++k) {
    if (bad[static_cast<size_t>(k)]) {
      EXPECT_GT(g.PriorError(k).norm(), 45.0) << "outlier fix " << k << " pulled the graph";
    } else {
      EXPECT_LT(g.PriorError(k).norm(), 2.5) << "fix " << k;
    }
  }
}

TEST(PoseGraph, PlainLeastSquaresPriorsFollowTheOutliers) {
  // The same graph with non-robust priors: the 50 m fixes drag their keyframes off (the reason for the loss).
  const int n = 100;
  const DriftingChain c = MakeDriftingChain(n, 0.01, 1e-3, 3);
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.AddNode(c.initial[static_cast<size_t>(i)], i == 0);
  for (int i = 0; i + 1 < n; ++i)
    g.AddRelativeEdge(i, i + 1, c.odometry[static_cast<size_t>(i)], OdometryInformation());
  for (int i = 1; i < n; ++i) {
    const Eigen::Vector3d offset = i % 20 == 7 ? Eigen::Vector3d(50, 0, 0) : Eigen::Vector3d::Zero();
    g.AddPositionPrior(i, c.truth[static_cast<size_t>(i)].translation + offset, 0.5, false);
  }
  PoseGraphOptions options;
  options.max_iterations = 50;
  g.Optimize(options);
  EXPECT_GT(MaxPositionError(g, c.truth), 2.0);
}

TEST(PoseGraph, LoopEdgeAndSparsePriorsTogether) {
  const int n = 100;
  const DriftingChain c = MakeDriftingChain(n, 0.01, 1e-3, 5);
  std::mt19937 rng(6);
  std::normal_distribution<double> gps_noise(0.0, 1.0);
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.AddNode(c.initial[static_cast<size_t>(i)], i == 0);
  for (int i = 0; i + 1 < n; ++i)
    g.AddRelativeEdge(i, i + 1, c.odometry[static_cast<size_t>(i)], OdometryInformation());
  g.AddRelativeEdge(n - 1, 0, TrueRelative(c, n - 1, 0), OdometryInformation());
  // A fix (sigma 1 m) every 10 keyframes, one of them 50 m off.
  for (int i = 5; i < n; i += 10) {
    Eigen::Vector3d target = c.truth[static_cast<size_t>(i)].translation + DrawVector3(gps_noise, rng);
    if (i == 55) target += Eigen::Vector3d(50, 0, 0);
    g.AddPositionPrior(i, target, 1.0);
  }
  PoseGraphOptions options;
  options.max_iterations = 50;
  g.Optimize(options);
  EXPECT_LT(MaxPositionError(g, c.truth), 1.0);
  EXPECT_GT(g.PriorError(5).norm(), 45.0);
}

TEST(PoseGraph, EstimatesThePriorFrameJointly) {
  const int n = 100;
  const DriftingChain c = MakeDriftingChain(n, 0.01, 1e-3, 7);
  // ENU targets: enu_from_world = rotation about the world's y (up is -y), 0.9 scale, far-away origin.
  const Sim3d enu_from_world(0.9, Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY())),
                             Eigen::Vector3d(350.0, -20.0, 1200.0));
  std::mt19937 rng(8);
  std::normal_distribution<double> gps_noise(0.0, 0.3);
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.AddNode(c.initial[static_cast<size_t>(i)], i == 0);
  for (int i = 0; i + 1 < n; ++i)
    g.AddRelativeEdge(i, i + 1, c.odometry[static_cast<size_t>(i)], OdometryInformation());
  std::vector<Eigen::Vector3d> enu_truth;
  for (int i = 0; i < n; ++i)
    enu_truth.push_back(enu_from_world * c.truth[static_cast<size_t>(i)].translation);
  for (int i = 0; i < n; i += 3) {
    g.AddPositionPrior(i, enu_truth[static_cast<size_t>(i)] + DrawVector3(gps_noise, rng), 0.3);
  }
  // Initial guess of a rough closed-form alignment: 10 % off in scale, 0.1 rad, 15 m.
  const Sim3d guess =
      Sim3d(1.1, QuaternionExp(Eigen::Vector3d(0.0, 0.1, 0.0)), Eigen::Vector3d(10, 0, -10)) * enu_from_world;
  g.EstimatePriorFrame(guess, false);
  PoseGraphOptions options;
  options.max_iterations = 100;
  g.Optimize(options);
  // The ENU positions are what the priors determine: fixing node 0 and freeing the frame is a gauge choice,
  // so they are the estimate of the graph in ENU, a few decimetres off where the fixes are dense, most at
  // the chain's ends.
  double worst = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d enu = g.prior_from_graph() * g.world_from_node(i).translation;
    const double e = (enu - enu_truth[static_cast<size_t>(i)]).norm();
    worst = std::max(worst, e);
    sum2 += e * e;
  }
  EXPECT_LT(worst, 1.0);
  EXPECT_LT(std::sqrt(sum2 / n), 0.4);
  // The frame itself is that of node 0 in ENU: its scale is the local map scale at the start, which the
  // drifting odometry pins down only roughly.
  const Sim3d& got = g.prior_from_graph();
  EXPECT_NEAR(got.scale, enu_from_world.scale, 0.1);
  EXPECT_LT(RotationError(got.rotation, enu_from_world.rotation), 0.03);
  EXPECT_LT((got.translation - enu_from_world.translation).norm(), 1.0);
}

TEST(PoseGraph, FixedScaleKeepsScaleOne) {
  // Stereo: rigid odometry with rotation and translation noise, a loop edge, SE(3) nodes.
  const int n = 60;
  std::mt19937 rng(9);
  const std::vector<Rigid3d> truth = LoopTrajectory(n);
  std::vector<Sim3d> initial = {Sim3d(truth[0])};
  PoseGraph g;
  g.AddNode(initial[0], true);
  for (int i = 0; i + 1 < n; ++i) {
    const Rigid3d rel = truth[static_cast<size_t>(i)].Inverse() * truth[static_cast<size_t>(i) + 1];
    const Rigid3d error = RandomRigid(rng, 0.004, 0.02);
    const Sim3d measured(1.0, error.rotation * rel.rotation, rel.translation + error.translation);
    initial.push_back(initial.back() * measured);
    g.AddNode(initial.back(), false);
    g.AddRelativeEdge(i, i + 1, measured);
  }
  g.AddRelativeEdge(n - 1, 0, Sim3d(truth[static_cast<size_t>(n) - 1].Inverse() * truth[0]), 10.0);
  PoseGraphOptions options;
  options.fix_scale = true;
  g.Optimize(options);
  for (int i = 0; i < n; ++i) EXPECT_EQ(g.world_from_node(i).scale, 1.0);
  EXPECT_LT(MaxPositionError(g, truth), 0.5 * MaxPositionError(initial, truth));
}

// Priors on a point a metre beside each node (an antenna beside the camera) place the nodes where that point
// meets its target; the same targets on the centres would leave the nodes that metre off.
TEST(PoseGraph, PositionPriorsOnAnOffsetPoint) {
  const std::vector<Rigid3d> truth = LoopTrajectory(40);
  const Eigen::Vector3d antenna(0.3, -0.9, -0.5);
  PoseGraph g;
  for (size_t i = 0; i < truth.size(); ++i) {
    // Started 2 m off, with the right relative poses between neighbours.
    g.AddNode(Sim3d(truth[i]) * Sim3d(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(2, 0, 0)), false);
  }
  for (int i = 0; i + 1 < g.num_nodes(); ++i) {
    g.AddRelativeEdge(i, i + 1,
                      Sim3d(truth[static_cast<size_t>(i)].Inverse() * truth[static_cast<size_t>(i) + 1]),
                      PoseGraph::EdgeInformation(0.01, 0.001, 0.001));
  }
  for (int i = 0; i < g.num_nodes(); i += 4) {
    g.AddPositionPrior(i, truth[static_cast<size_t>(i)] * antenna, 0.05, true, antenna);
  }
  PoseGraphOptions options;
  options.fix_scale = true;
  options.max_iterations = 50;
  g.Optimize(options);
  EXPECT_LT(MaxPositionError(g, truth), 0.01);
  for (int p = 0; p < g.num_priors(); ++p) EXPECT_LT(g.PriorError(p).norm(), 0.01);
  PoseGraph framed;
  framed.AddNode(Sim3d(), true);
  framed.AddPositionPrior(0, Eigen::Vector3d::Zero(), 1.0, true, antenna);
  framed.EstimatePriorFrame(Sim3d(), false);
  EXPECT_THROW(framed.Optimize(), InvalidArgument);  // an offset needs the graph's own metric frame
}

TEST(PoseGraph, RejectsBadInput) {
  PoseGraph g;
  const int a = g.AddNode(Sim3d(), false);
  const int b = g.AddNode(Sim3d(), false);
  EXPECT_THROW(g.AddRelativeEdge(a, 5, Sim3d()), InvalidArgument);
  EXPECT_THROW(g.AddRelativeEdge(a, a, Sim3d()), InvalidArgument);
  EXPECT_THROW(g.AddRelativeEdge(a, b, Sim3d(), 0.0), InvalidArgument);
  EXPECT_THROW(g.AddRelativeEdge(a, b, Sim3d(0.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero())),
               InvalidArgument);
  EXPECT_THROW(g.AddPositionPrior(b, Eigen::Vector3d::Zero(), -1.0), InvalidArgument);
  EXPECT_THROW(g.AddDirectionPrior(b, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 0.1),
               InvalidArgument);
  EXPECT_THROW(g.AddDirectionPrior(b, Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ(), 0.0),
               InvalidArgument);
  EXPECT_THROW(
      g.AddNode(Sim3d(1.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::nan(""), 0, 0)), false),
      InvalidArgument);
  g.AddRelativeEdge(a, b, Sim3d());
  EXPECT_THROW(g.Optimize(), InvalidArgument);  // nothing anchors the gauge
  g.AddPositionPrior(a, Eigen::Vector3d::Zero(), 1.0);
  g.EstimatePriorFrame(Sim3d(), false);
  EXPECT_THROW(g.Optimize(), InvalidArgument);  // prior frame without a fixed node
  EXPECT_THROW(g.world_from_node(7), InvalidArgument);
}

}  // namespace
}  // namespace semslam
