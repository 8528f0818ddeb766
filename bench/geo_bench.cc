// Speed of the geo side after SLAM: GPS alignment and pose-graph fusion, local corrections, landmarks,
// topology, DBSCAN objects. `build/release/bench/geo_bench`.

#include <benchmark/benchmark.h>
#include <fmt/format.h>

#include <cmath>
#include <random>
#include <vector>

#include "semslam/geo/gps_alignment.h"
#include "semslam/geo/gps_fusion.h"
#include "semslam/landmarks/landmark_map.h"
#include "semslam/objects/object_map.h"
#include "semslam/topology/topological_map.h"

namespace semslam {
namespace {

// A drive around blocks of 200 x 150 m (a frame per metre, 10 Hz), its map with 1 %/100 m scale drift, and
// GPS fixes (sigma 1 m) every 30 frames.
struct Drive {
  EnuFrame enu{Wgs84{49.0, 8.4, 115.0}};
  Points3d truth;
  std::vector<FramePose> frames;
  std::vector<GpsFix> fixes;
};

Drive MakeDrive(int laps) {
  Drive d;
  const std::vector<Eigen::Vector2d> corners = {{0, 0}, {200, 0}, {200, 150}, {0, 150}};
  for (int lap = 0; lap < laps; ++lap) {
    for (size_t c = 0; c < corners.size(); ++c) {
      const Eigen::Vector2d a = corners[c],
                            b = corners[(c + 1) % corners.size()] + Eigen::Vector2d(0, lap * 5.0);
      const int n = static_cast<int>((b - a).norm());
      for (int i = 0; i < n; ++i) {
        const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / n);
        d.truth.emplace_back(p.x(), p.y(), 0.0);
      }
    }
  }
  std::mt19937 rng(1);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<Rigid3d> truth_pose;
  for (size_t i = 0; i < d.truth.size(); ++i) {
    const Eigen::Vector3d dir =
        (d.truth[std::min(i + 1, d.truth.size() - 1)] - d.truth[i > 0 ? i - 1 : 0]).normalized();
    Eigen::Matrix3d r;
    r << dir.cross(Eigen::Vector3d::UnitZ()), -Eigen::Vector3d::UnitZ(), dir;
    truth_pose.emplace_back(r, d.truth[i]);
  }
  Rigid3d map_from_camera;
  double travelled = 0.0;
  for (size_t i = 0; i < d.truth.size(); ++i) {
    if (i > 0) {
      Rigid3d step = truth_pose[i - 1].Inverse() * truth_pose[i];
      travelled += step.translation.norm();
      step.translation *= 0.05 * std::pow(1.01, travelled / 100.0);  // map units; the scale drifts
      map_from_camera = map_from_camera * step;
    }
    d.frames.push_back(FramePose{i, -1, 0.1 * static_cast<double>(i), map_from_camera});
    if (i % 30 == 0) {
      const Eigen::Vector3d fix = d.truth[i] + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      d.fixes.push_back(GpsFix{0.1 * static_cast<double>(i), d.enu.ToWgs84(fix), 1.0, {}});
    }
  }
  return d;
}

GpsFusionInput FusionInput(const Drive& d) {
  GpsFusionInput input;
  input.frames = d.frames;
  for (size_t i = 0; i < d.frames.size(); i += 5) input.keyframes.push_back(d.frames[i]);
  input.fixes = d.fixes;
  return input;
}

void BM_AlignMapToGps(benchmark::State& state) {
  const Drive d = MakeDrive(static_cast<int>(state.range(0)));
  const auto samples = SampleGpsPairs(Positions(d.frames), d.fixes, d.enu, {});
  for (auto _ : state) benchmark::DoNotOptimize(AlignMapToGps(samples));
  state.counters["samples"] = static_cast<double>(samples.size());
}
BENCHMARK(BM_AlignMapToGps)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond);

void BM_FuseGps(benchmark::State& state) {
  const Drive d = MakeDrive(static_cast<int>(state.range(0)));
  const GpsFusionInput input = FusionInput(d);
  for (auto _ : state) benchmark::DoNotOptimize(FuseGps(input, d.enu));
  state.counters["keyframes"] = static_cast<double>(input.keyframes.size());
}
BENCHMARK(BM_FuseGps)->Arg(1)->Arg(4)->Unit(benchmark::kMillisecond);

void BM_LocalCorrectionsMapToEnu(benchmark::State& state) {
  const Drive d = MakeDrive(4);
  const auto result = FuseGps(FusionInput(d), d.enu);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1.0, 12.0);
  Points3d points(10000);
  for (Eigen::Vector3d& p : points) p = Eigen::Vector3d(u(rng), u(rng), u(rng) * 0.1);
  for (auto _ : state) {
    for (const Eigen::Vector3d& p : points) benchmark::DoNotOptimize(result->georeference.MapToEnu(p));
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(points.size()));
  state.counters["nodes"] = static_cast<double>(result->georeference.local->keyframes().size());
}
BENCHMARK(BM_LocalCorrectionsMapToEnu)->Unit(benchmark::kMillisecond);

void BM_LandmarksAndTopology(benchmark::State& state) {
  const Drive d = MakeDrive(4);
  const auto result = FuseGps(FusionInput(d), d.enu);
  const Georeference& g = result->georeference;
  FramePositions keyframes;
  for (size_t i = 0; i < d.frames.size(); i += 5) keyframes.push_back(d.frames[i].Position());
  std::vector<Landmark> catalogue;
  for (int i = 0; i < 50; ++i) {
    Landmark l;
    l.name = fmt::format("L{}", i);  // (std::string + std::to_string trips GCC 12 -Wrestrict at -O3)
    l.position = d.enu.ToWgs84(Eigen::Vector3d(4.0 * i, 10.0 + (i % 3) * 60.0, 0.0));
    catalogue.push_back(l);
  }
  for (auto _ : state) {
    const auto placed = PlaceLandmarks(catalogue, g, keyframes);
    benchmark::DoNotOptimize(BuildTopologicalMap(keyframes, placed, g));
  }
}
BENCHMARK(BM_LandmarksAndTopology)->Unit(benchmark::kMillisecond);

void BM_MembershipRaster(benchmark::State& state) {
  const Georeference g(EnuFrame(Wgs84{49.0, 8.4, 115.0}), Sim3d());
  std::vector<PlacedLandmark> landmarks(20);
  for (size_t i = 0; i < landmarks.size(); ++i)
    landmarks[i].enu = Eigen::Vector3d(30.0 * static_cast<double>(i), 50.0, 0.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(RasterizeMembership(landmarks, {-100, -100}, {700, 300}, 2.0, 25.0));
  }
}
BENCHMARK(BM_MembershipRaster)->Unit(benchmark::kMillisecond);

void BM_ObjectMap(benchmark::State& state) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<LabeledPoint> points;
  const int n = static_cast<int>(state.range(0));
  for (int i = 0; i < n; ++i) {
    const int label = static_cast<int>(u(rng) * kNumClasses) % kNumClasses;
    // Clustered: around 200 centres in a 400 x 400 m area.
    const int centre = static_cast<int>(u(rng) * 200);
    const Eigen::Vector3d c(2.0 * centre, 400.0 * std::fmod(centre * 0.618, 1.0), 1.0);
    points.push_back(LabeledPoint{c + Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3.0, label, 0.9});
  }
  for (auto _ : state) benchmark::DoNotOptimize(BuildObjectMap(points));
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_ObjectMap)->Arg(10000)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace semslam

BENCHMARK_MAIN();
