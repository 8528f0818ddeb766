// Geometric solvers on synthetic data: two-view initialization (1000 matches, 20 % outliers), PnP RANSAC
// (300 correspondences, 30 % outliers) and Sim(3) RANSAC (100 matches, 30 % outliers). Each iteration uses a
// different RANSAC seed on the same data.
//
//   build/release/bench/geometry_bench
//   build/release/bench/geometry_bench --benchmark_filter=TwoView

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/pnp.h"
#include "semslam/geometry/sim3_solver.h"
#include "semslam/geometry/two_view.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

Rigid3d Camera2FromCamera1() {
  const Eigen::Quaterniond rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(3 * kDeg, Eigen::Vector3d::UnitY())) *
      Eigen::AngleAxisd(-1 * kDeg, Eigen::Vector3d::UnitX());
  return Rigid3d(rotation, Eigen::Vector3d(1.0, 0.05, 0.4)).Inverse();
}

struct TwoViewData {
  PinholeCamera camera = KittiCamera();
  Points2d pixels1, pixels2;
};

// Points 5..40 m ahead seen from two views 1.1 m apart, 0.5 px noise, a fraction of random matches.
TwoViewData MakeTwoView(int count, double outlier_ratio) {
  TwoViewData data;
  const Rigid3d motion = Camera2FromCamera1();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, data.camera.width - 1.0), v(0.0, data.camera.height - 1.0);
  std::uniform_real_distribution<double> depth(5.0, 40.0), unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  while (static_cast<int>(data.pixels1.size()) < count) {
    const Eigen::Vector2d pixel(u(rng), v(rng));
    const auto pixel2 = data.camera.ProjectIfVisible(motion * data.camera.UnprojectDepth(pixel, depth(rng)));
    if (!pixel2) continue;
    data.pixels1.push_back(pixel + Eigen::Vector2d(noise(rng), noise(rng)));
    data.pixels2.push_back(unit(rng) < outlier_ratio
                               ? Eigen::Vector2d(u(rng), v(rng))
                               : Eigen::Vector2d(*pixel2 + Eigen::Vector2d(noise(rng), noise(rng))));
  }
  return data;
}

void BM_InitializeTwoView(benchmark::State& state) {
  const TwoViewData data = MakeTwoView(static_cast<int>(state.range(0)), 0.2);
  TwoViewOptions options;
  options.parallel = state.range(1) != 0;
  int successes = 0;
  for (auto _ : state) {
    options.seed += 1;
    const TwoViewResult result = InitializeTwoView(data.pixels1, data.pixels2, data.camera, options);
    successes += result.success ? 1 : 0;
    benchmark::DoNotOptimize(result);
  }
  state.counters["success_rate"] = static_cast<double>(successes) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_InitializeTwoView)
    ->Args({1000, 1})
    ->Args({1000, 0})
    ->ArgNames({"matches", "parallel"})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

struct PnpData {
  Points3d world_points, bearings;
};

// Points 3..30 m in front of a camera at some pose, 0.5 px noise, a fraction of random bearings.
PnpData MakePnp(int count, double outlier_ratio) {
  const PinholeCamera camera = KittiCamera();
  const Rigid3d world_from_camera(
      Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, 1, 0.1).normalized())),
      Eigen::Vector3d(3, -1, 12));
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0.0, camera.width - 1.0), v(0.0, camera.height - 1.0);
  std::uniform_real_distribution<double> depth(3.0, 30.0), unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.5);
  PnpData data;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector2d pixel(u(rng), v(rng));
    data.world_points.push_back(world_from_camera * camera.UnprojectDepth(pixel, depth(rng)));
    const Eigen::Vector2d observed = unit(rng) < outlier_ratio
                                         ? Eigen::Vector2d(u(rng), v(rng))
                                         : Eigen::Vector2d(pixel + Eigen::Vector2d(noise(rng), noise(rng)));
    data.bearings.push_back(camera.Unproject(observed));
  }
  return data;
}

void BM_SolvePnpRansac(benchmark::State& state) {
  const PnpData data = MakePnp(static_cast<int>(state.range(0)), 0.3);
  PnpRansacOptions options;
  options.focal_length = KittiCamera().fx;
  double iterations = 0;
  for (auto _ : state) {
    options.seed += 1;
    const auto result = SolvePnpRansac(data.world_points, data.bearings, options);
    if (result) iterations += result->iterations;
    benchmark::DoNotOptimize(result);
  }
  state.counters["ransac_iterations"] = iterations / static_cast<double>(state.iterations());
}
BENCHMARK(BM_SolvePnpRansac)->Arg(300)->ArgName("correspondences")->Unit(benchmark::kMicrosecond);

// Matched map points of two keyframes related by a similarity (scale 1.3), keypoints at pyramid levels 0..3,
// 0.5 % depth noise, a fraction of wrong matches.
Sim3Correspondences MakeSim3(int count, double outlier_ratio) {
  const Sim3d camera1_from_camera2(
      1.3, Eigen::Quaterniond(Eigen::AngleAxisd(10 * kDeg, Eigen::Vector3d(0.1, 1.0, 0.2).normalized())),
      Eigen::Vector3d(0.8, 0.1, -1.5));
  Sim3Correspondences c;
  c.camera1 = c.camera2 = KittiCamera();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, c.camera2.width - 1.0), v(0.0, c.camera2.height - 1.0);
  std::uniform_real_distribution<double> depth(4.0, 30.0), unit(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, 3);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto random_point2 = [&] {
    while (true) {
      const Eigen::Vector3d p = c.camera2.UnprojectDepth({u(rng), v(rng)}, depth(rng));
      if (c.camera1.ProjectIfVisible(camera1_from_camera2 * p)) return p;
    }
  };
  const auto observe = [&](const PinholeCamera& camera, const Eigen::Vector3d& p,
                           std::vector<double>& sigma2) {
    sigma2.push_back(std::pow(1.2, 2 * level(rng)));
    return Eigen::Vector2d(camera.Project(p) +
                           std::sqrt(sigma2.back()) * Eigen::Vector2d(normal(rng), normal(rng)));
  };
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3d p2 = random_point2();
    const Eigen::Vector3d p1 = camera1_from_camera2 * p2;
    c.pixels1.push_back(observe(c.camera1, p1, c.sigma2_1));
    c.points1.push_back(p1 * (1.0 + 0.005 * normal(rng)));
    const Eigen::Vector3d q2 = unit(rng) < outlier_ratio ? random_point2() : p2;
    c.pixels2.push_back(observe(c.camera2, q2, c.sigma2_2));
    c.points2.push_back(q2 * (1.0 + 0.005 * normal(rng)));
  }
  return c;
}

void BM_EstimateSim3Ransac(benchmark::State& state) {
  const Sim3Correspondences c = MakeSim3(static_cast<int>(state.range(0)), 0.3);
  Sim3RansacOptions options;
  options.fix_scale = state.range(1) != 0;
  double iterations = 0;
  for (auto _ : state) {
    options.seed += 1;
    const auto result = EstimateSim3Ransac(c, options);
    if (result) iterations += result->iterations;
    benchmark::DoNotOptimize(result);
  }
  state.counters["ransac_iterations"] = iterations / static_cast<double>(state.iterations());
}
BENCHMARK(BM_EstimateSim3Ransac)
    ->Args({100, 0})
    ->ArgNames({"matches", "fix_scale"})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace semslam

BENCHMARK_MAIN();
