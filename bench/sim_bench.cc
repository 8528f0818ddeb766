// Synthetic city speed: rendering a KITTI-size frame (left + right + labels + depth) on 1 and 2 threads,
// with and without writing its four PNGs, and generating the town and route. Counter fps = frames per second
// (wall clock).
//
//   build/release/bench/sim_bench                       # all
//   build/release/bench/sim_bench --benchmark_filter=Render

#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <filesystem>
#include <memory>

#include "semslam/sim/dataset_writer.h"
#include "semslam/sim/synthetic_city.h"

namespace semslam::sim {
namespace {

const SyntheticCity& City() {
  static const SyntheticCity city([] {
    SynthOptions o = PresetOptions("default");
    o.route.frames = 1200;
    return o;
  }());
  return city;
}

// Frames spread over the drive (straight streets, turns, the revisit).
size_t FrameAt(size_t i) { return (i * 37) % City().num_frames(); }

void BM_RenderFrame(benchmark::State& state) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    static_cast<size_t>(state.range(0)));
  const SyntheticCity& sim = City();
  size_t i = 0;
  for (auto _ : state) {
    RenderedFrame frame = sim.Render(FrameAt(i++), kRenderAll);
    benchmark::DoNotOptimize(frame.left.data);
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderFrame)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(5.0);

void BM_RenderLeftOnly(benchmark::State& state) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism, 2);
  const SyntheticCity& sim = City();
  size_t i = 0;
  for (auto _ : state) {
    RenderedFrame frame = sim.Render(FrameAt(i++), kRenderLeft);
    benchmark::DoNotOptimize(frame.left.data);
  }
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderLeftOnly)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(3.0);

// Rendering and writing image_0, image_1, label_0 and depth_0 (PNG level 1, atomic files), frames in
// parallel as `semslam synth` does.
void BM_RenderAndWriteFrames(benchmark::State& state) {
  const tbb::global_control threads(tbb::global_control::max_allowed_parallelism,
                                    static_cast<size_t>(state.range(0)));
  const SyntheticCity& sim = City();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "semslam_sim_bench";
  for (const char* sub : {"image_0", "image_1", "label_0", "depth_0"})
    std::filesystem::create_directories(dir / sub);
  size_t i = 0;
  for (auto _ : state) WriteFrame(sim, FrameAt(i++), dir);
  std::filesystem::remove_all(dir);
  state.counters["fps"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_RenderAndWriteFrames)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(5.0);

void BM_GenerateTownAndRoute(benchmark::State& state) {
  for (auto _ : state) {
    SynthOptions o = PresetOptions("default");
    o.route.frames = static_cast<int>(state.range(0));
    const SyntheticCity sim(o);
    benchmark::DoNotOptimize(sim.num_frames());
  }
}
BENCHMARK(BM_GenerateTownAndRoute)->Arg(1200)->Arg(3000)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace semslam::sim

BENCHMARK_MAIN();
