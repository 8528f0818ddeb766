// Optimizer speed on synthetic problems of the sizes the SLAM core produces: motion-only pose optimization
// (several per tracked frame), ORB-SLAM-sized local bundle adjustment, a 1000-node essential graph with and
// without GPS position priors, and the Sim(3) refinement of a loop candidate.
//
//   build/release/bench/optim_bench                             # all
//   build/release/bench/optim_bench --benchmark_filter=Pose     # motion-only BA only

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "semslam/optim/bundle_adjustment.h"
#include "semslam/optim/pose_graph.h"
#include "semslam/optim/pose_optimization.h"
#include "semslam/optim/sim3_optimization.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

Eigen::Vector3d Gaussian3(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(rng), n(rng), n(rng)};
}

Eigen::Vector3d CameraPoint(std::mt19937& rng, const PinholeCamera& c, double min_depth, double max_depth) {
  std::uniform_real_distribution<double> u(5.0, c.width - 6.0), v(5.0, c.height - 6.0),
      z(min_depth, max_depth);
  return c.UnprojectDepth({u(rng), v(rng)}, z(rng));
}

// Tracking: n matches to map points 4-40 m away, keypoints on levels 0-7 with their level's noise, 10 % wrong
// matches, the motion-model guess 0.05 rad / 0.3 m off.
PoseOptimizationProblem PoseProblem(int n, bool stereo) {
  std::mt19937 rng(42);
  PoseOptimizationProblem p;
  p.camera = KittiCamera();
  p.baseline = stereo ? 0.54 : 0.0;
  const Rigid3d truth(QuaternionExp(Eigen::Vector3d(0.02, -0.3, 0.01)), Eigen::Vector3d(1.0, -0.2, 3.0));
  std::uniform_int_distribution<int> level(0, 7);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, 1);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d pc = CameraPoint(rng, p.camera, 4.0, 40.0);
    const double sigma = std::pow(1.2, level(rng));
    PoseObservation o;
    o.point = truth.Inverse() * pc;
    o.inv_sigma2 = 1.0 / (sigma * sigma);
    o.pixel = p.camera.Project(pc) + sigma * Eigen::Vector2d(noise(rng), noise(rng));
    if (stereo) o.right_u = p.camera.Project(pc).x() - p.camera.fx * p.baseline / pc.z() + sigma * noise(rng);
    if (unit(rng) < 0.1) o.pixel += Eigen::Vector2d(60.0, -40.0);
    p.observations.push_back(o);
  }
  p.camera_from_world = Rigid3d(QuaternionExp(Gaussian3(rng, 0.03)), Gaussian3(rng, 0.17)) * truth;
  return p;
}

void BM_OptimizePose(benchmark::State& state) {
  const PoseOptimizationProblem problem = PoseProblem(static_cast<int>(state.range(0)), state.range(1) != 0);
  PoseOptimizationOptions options;
  options.solver = state.range(2) != 0 ? PoseSolver::kCeres : PoseSolver::kGaussNewton;
  int inliers = 0;
  for (auto _ : state) {
    const PoseOptimizationResult r = OptimizePose(problem, options);
    inliers = r.num_inliers;
    benchmark::DoNotOptimize(r);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_OptimizePose)
    ->ArgNames({"observations", "stereo", "ceres"})
    ->Args({300, 0, 0})
    ->Args({500, 0, 0})
    ->Args({1000, 0, 0})
    ->Args({500, 1, 0})
    ->Args({300, 0, 1})
    ->Args({500, 0, 1})
    ->Args({1000, 0, 1})
    ->Args({500, 1, 1})
    ->Unit(benchmark::kMicrosecond);

// Local BA as the local mapper builds it: 10 free keyframes (the current one and its covisibles) and 10
// fixed ones that also see their points, 1.5 m apart along a drive; 3000 points seen by 5 consecutive
// keyframes each (15000 observations), 1 px noise, 3 % wrong observations; poses and points perturbed.
BundleAdjustmentProblem LocalBaProblem(bool stereo) {
  std::mt19937 rng(7);
  BundleAdjustmentProblem p;
  p.camera = KittiCamera();
  p.baseline = stereo ? 0.54 : 0.0;
  const int num_keyframes = 20;
  std::vector<Rigid3d> truth;
  for (int i = 0; i < num_keyframes; ++i) {
    const Rigid3d world_from_camera(QuaternionExp(Eigen::Vector3d(0, 0.02 * std::sin(0.4 * i), 0)),
                                    Eigen::Vector3d(0.3 * std::sin(0.3 * i), 0.0, 1.5 * i));
    truth.push_back(world_from_camera.Inverse());
    const bool fixed = i < 10;  // the older keyframes
    p.pose_fixed.push_back(fixed);
    p.camera_from_world.push_back(
        fixed ? truth.back()
              : Rigid3d(QuaternionExp(Gaussian3(rng, 0.003)), Gaussian3(rng, 0.03)) * truth.back());
  }
  std::uniform_int_distribution<int> first(0, num_keyframes - 5);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> noise(0, 1);
  while (p.points.size() < 3000) {
    const int start = first(rng);
    // A point seen by keyframe `start + 4` (the last of its window), also in front of the earlier ones.
    const Rigid3d& last = truth[static_cast<size_t>(start) + 4];
    const Eigen::Vector3d world = last.Inverse() * CameraPoint(rng, p.camera, 6.0, 40.0);
    std::vector<BundleAdjustmentObservation> seen;
    for (int i = start; i < start + 5; ++i) {
      const Eigen::Vector3d pc = truth[static_cast<size_t>(i)] * world;
      if (pc.z() < 1.0 || !p.camera.InImage(p.camera.Project(pc))) break;
      BundleAdjustmentObservation o;
      o.pose = i;
      o.point = static_cast<int>(p.points.size());
      o.pixel = p.camera.Project(pc) + Eigen::Vector2d(noise(rng), noise(rng));
      if (stereo && pc.z() < 25.0)
        o.right_u = p.camera.Project(pc).x() - p.camera.fx * p.baseline / pc.z() + noise(rng);
      if (unit(rng) < 0.03) o.pixel += Eigen::Vector2d(25.0, 30.0);
      seen.push_back(o);
    }
    if (seen.size() < 5) continue;
    p.observations.insert(p.observations.end(), seen.begin(), seen.end());
    p.points.push_back(world + Gaussian3(rng, 0.05));
  }
  return p;
}

void BM_LocalBundleAdjustment(benchmark::State& state) {
  const BundleAdjustmentProblem problem = LocalBaProblem(state.range(1) != 0);
  BundleAdjustmentOptions options;
  options.iterations = 5;  // ORB-SLAM's local BA: 5 iterations, drop outliers, 10 more
  options.refine_without_outliers = true;
  options.refine_iterations = 10;
  options.solver = static_cast<BundleAdjustmentSolver>(state.range(0));
  options.num_threads = static_cast<int>(state.range(2));
  BundleAdjustmentResult result;
  for (auto _ : state) {
    state.PauseTiming();
    BundleAdjustmentProblem p = problem;
    state.ResumeTiming();
    result = BundleAdjust(p, options);
    benchmark::DoNotOptimize(p);
  }
  state.counters["observations"] = static_cast<double>(problem.observations.size());
  state.counters["outliers"] = result.num_outliers;
  state.counters["iterations"] = result.iterations;
  state.counters["initial_rms"] = result.initial_rms;
  state.counters["final_rms"] = result.final_rms;
}
BENCHMARK(BM_LocalBundleAdjustment)
    ->ArgNames({"solver", "stereo", "threads"})  // solver: 1 dense Schur, 2 sparse Schur, 3 iterative Schur
    ->Args({static_cast<int>(BundleAdjustmentSolver::kDenseSchur), 0, 1})
    ->Args({static_cast<int>(BundleAdjustmentSolver::kSparseSchur), 0, 1})
    ->Args({static_cast<int>(BundleAdjustmentSolver::kIterativeSchur), 0, 1})
    ->Args({static_cast<int>(BundleAdjustmentSolver::kDenseSchur), 1, 1})
    ->Args({static_cast<int>(BundleAdjustmentSolver::kDenseSchur), 0, 2})
    ->Unit(benchmark::kMillisecond);

// The essential graph after a loop of 1000 keyframes: spanning tree (odometry with 1 %/step scale drift),
// covisibility edges to the next 2-3 keyframes, and the loop edge; optionally a GPS fix every 10 keyframes
// (5 % of them 50 m off).
PoseGraph EssentialGraph(int n, bool priors) {
  std::mt19937 rng(3);
  std::vector<Rigid3d> truth;
  for (int i = 0; i < n; ++i) {
    const double theta = 2.0 * M_PI * i / n;
    const double radius = 1.5 * n / (2.0 * M_PI);
    truth.emplace_back(Eigen::Quaterniond(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitY())),
                       Eigen::Vector3d(radius * (1.0 - std::cos(theta)), 0.0, radius * std::sin(theta)));
  }
  auto local_scale = [](int i) { return std::pow(1.001, i); };  // 1000 steps: 2.7x
  auto node = [&](int i) {
    return Sim3d(1.0 / local_scale(i), truth[static_cast<size_t>(i)].rotation,
                 truth[static_cast<size_t>(i)].translation);
  };
  auto measured = [&](int a, int b) {
    // Believed scale ratio 1 (the drift), small noise.
    const Sim3d rel = node(a).Inverse() * node(b);
    return Sim3d(1.0, QuaternionExp(Gaussian3(rng, 1e-3)) * rel.rotation,
                 rel.translation + Gaussian3(rng, 1e-3));
  };
  PoseGraph g;
  Sim3d current(truth[0]);
  g.AddNode(current, true);
  for (int i = 1; i < n; ++i) {
    current = current * measured(i - 1, i);
    g.AddNode(current, false);
  }
  const auto information = PoseGraph::EdgeInformation(0.02, 0.002, 0.05);
  for (int i = 0; i + 1 < n; ++i) {
    for (int k = 1; k <= 3 && i + k < n; ++k) {
      if (priors) {
        g.AddRelativeEdge(i, i + k, measured(i, i + k), information);
      } else {
        g.AddRelativeEdge(i, i + k, measured(i, i + k));
      }
    }
  }
  g.AddRelativeEdge(n - 1, 0, node(n - 1).Inverse() * node(0));
  if (priors) {
    std::uniform_real_distribution<double> unit(0, 1);
    for (int i = 5; i < n; i += 10) {
      Eigen::Vector3d target = truth[static_cast<size_t>(i)].translation + Gaussian3(rng, 1.0);
      if (unit(rng) < 0.05) target += Eigen::Vector3d(50.0, 0.0, 0.0);
      g.AddPositionPrior(i, target, 1.0);
    }
  }
  return g;
}

void BM_PoseGraph(benchmark::State& state) {
  const PoseGraph graph = EssentialGraph(static_cast<int>(state.range(0)), state.range(1) != 0);
  PoseGraphOptions options;
  options.max_iterations = 20;
  PoseGraphSummary summary;
  for (auto _ : state) {
    state.PauseTiming();
    PoseGraph g = graph;
    state.ResumeTiming();
    summary = g.Optimize(options);
    benchmark::DoNotOptimize(g);
  }
  state.counters["nodes"] = graph.num_nodes();
  state.counters["edges"] = graph.num_edges();
  state.counters["priors"] = graph.num_priors();
  state.counters["iterations"] = summary.iterations;
}
BENCHMARK(BM_PoseGraph)
    ->ArgNames({"nodes", "priors"})
    ->Args({1000, 0})
    ->Args({1000, 1})
    ->Unit(benchmark::kMillisecond);

void BM_OptimizeSim3(benchmark::State& state) {
  std::mt19937 rng(5);
  Sim3RefinementProblem p;
  p.camera1 = p.camera2 = KittiCamera();
  const Sim3d truth(0.8, QuaternionExp(Eigen::Vector3d(0.01, 0.15, -0.02)), Eigen::Vector3d(0.8, 0.1, -1.5));
  std::normal_distribution<double> noise(0, 1);
  while (static_cast<int>(p.matches.size()) < state.range(0)) {
    const Eigen::Vector3d p2 = CameraPoint(rng, p.camera2, 5.0, 30.0);
    const Eigen::Vector3d p1 = truth * p2;
    if (p1.z() < 1.0 || !p.camera1.InImage(p.camera1.Project(p1))) continue;
    Sim3Match m;
    m.point1 = p1;
    m.point2 = p2;
    m.pixel1 = p.camera1.Project(p1) + Eigen::Vector2d(noise(rng), noise(rng));
    m.pixel2 = p.camera2.Project(p2) + Eigen::Vector2d(noise(rng), noise(rng));
    if (p.matches.size() % 10 == 3) m.pixel2 += Eigen::Vector2d(40, 40);
    p.matches.push_back(m);
  }
  const Sim3d initial =
      Sim3d(1.05, QuaternionExp(Eigen::Vector3d(0.02, -0.03, 0.01)), Eigen::Vector3d(0.2, -0.1, 0.3)) * truth;
  int inliers = 0;
  for (auto _ : state) {
    const Sim3RefinementResult r = OptimizeSim3(p, initial, 10.0, false);
    inliers = r.num_inliers;
    benchmark::DoNotOptimize(r);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_OptimizeSim3)->ArgNames({"matches"})->Arg(100)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace semslam

BENCHMARK_MAIN();
