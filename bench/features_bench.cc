// Feature extraction, stereo matching and bag-of-words speed on real KITTI frames, with OpenCV's ORB as the
// reference. Per-frame times are summarized as median and p95 (counters median_ms, p95_ms).
//
//   build/release/bench/features_bench                      # all
//   build/release/bench/features_bench --benchmark_filter=Extract

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "semslam/features/orb_extractor.h"
#include "semslam/features/orb_pattern.h"
#include "semslam/features/stereo_matching.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/vocabulary.h"

namespace semslam {
namespace {

// ../shared/data, or $SEMSLAM_SHARED_DATA.
std::filesystem::path SharedData() {
  if (const char* env = std::getenv("SEMSLAM_SHARED_DATA"); env != nullptr && *env != '\0') return env;
  return SEMSLAM_SHARED_DATA_DIR;
}
const std::filesystem::path kSequence = SharedData() / "kitti_odom_07_3dv" / "sequences" / "07" / "image_0";

// KITTI 07 frames 0..159 (1226x370), loaded once.
const std::vector<cv::Mat>& Frames() {
  static const std::vector<cv::Mat> frames = [] {
    std::vector<cv::Mat> out;
    for (int i = 0; i < 160; ++i) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", i);
      cv::Mat image = cv::imread((kSequence / name).string(), cv::IMREAD_GRAYSCALE);
      if (!image.empty()) out.push_back(image);
    }
    return out;
  }();
  return frames;
}

// Times each iteration on its own and reports median / p95 / mean in milliseconds.
class FrameTimer {
 public:
  void Start() { start_ = Clock::now(); }
  void Stop() {
    samples_.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start_).count());
  }
  void Report(benchmark::State& state) {
    if (samples_.empty()) return;
    std::sort(samples_.begin(), samples_.end());
    state.counters["median_ms"] = samples_[samples_.size() / 2];
    state.counters["p95_ms"] = samples_[std::min(samples_.size() - 1, samples_.size() * 95 / 100)];
    double sum = 0;
    for (const double s : samples_) sum += s;
    state.counters["mean_ms"] = sum / static_cast<double>(samples_.size());
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
  std::vector<double> samples_;
};

bool NeedFrames(benchmark::State& state) {
  if (Frames().empty()) {
    state.SkipWithError(("KITTI 07 frames missing: " + kSequence.string()).c_str());
    return false;
  }
  return true;
}

void BM_ExtractSemslam(benchmark::State& state) {
  if (!NeedFrames(state)) return;
  OrbOptions options;
  options.num_features = static_cast<int>(state.range(0));
  options.parallel = state.range(1) != 0;
  const OrbExtractor extractor(options);
  FrameTimer timer;
  size_t i = 0, features = 0;
  for (auto _ : state) {
    const cv::Mat& frame = Frames()[i++ % Frames().size()];
    timer.Start();
    FeatureSet f = extractor.Extract(frame);
    timer.Stop();
    features += f.size();
    benchmark::DoNotOptimize(f);
  }
  timer.Report(state);
  state.counters["features"] = static_cast<double>(features) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_ExtractSemslam)
    ->ArgNames({"features", "parallel"})
    ->Args({2000, 1})
    ->Args({2000, 0})
    ->Args({1000, 1})
    ->Args({4000, 1})
    ->Iterations(320)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_ExtractOpenCvOrb(benchmark::State& state) {
  if (!NeedFrames(state)) return;
  auto orb =
      cv::ORB::create(static_cast<int>(state.range(0)), 1.2f, 8, 31, 0, 2, cv::ORB::HARRIS_SCORE, 31, 20);
  FrameTimer timer;
  size_t i = 0, features = 0;
  for (auto _ : state) {
    const cv::Mat& frame = Frames()[i++ % Frames().size()];
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;
    timer.Start();
    orb->detectAndCompute(frame, cv::noArray(), keypoints, descriptors);
    timer.Stop();
    features += keypoints.size();
  }
  timer.Report(state);
  state.counters["features"] = static_cast<double>(features) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_ExtractOpenCvOrb)
    ->ArgNames({"features"})
    ->Arg(2000)
    ->Arg(1000)
    ->Iterations(320)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Our keypoints described by cv::ORB (the DBoW2-compatible option).
void BM_ExtractSemslamOpenCvPattern(benchmark::State& state) {
  if (!NeedFrames(state)) return;
  OrbOptions options;
  options.pattern = OrbDescriptorPattern::kOpenCv;
  const OrbExtractor extractor(options);
  FrameTimer timer;
  size_t i = 0;
  for (auto _ : state) {
    const cv::Mat& frame = Frames()[i++ % Frames().size()];
    timer.Start();
    FeatureSet f = extractor.Extract(frame);
    timer.Stop();
    benchmark::DoNotOptimize(f);
  }
  timer.Report(state);
}
BENCHMARK(BM_ExtractSemslamOpenCvPattern)->Iterations(160)->Unit(benchmark::kMillisecond)->UseRealTime();

// Stereo matching of a KITTI frame against itself shifted by 20.3 pixels (real texture, known disparity),
// given both pyramids: the part of stereo tracking after the two extractions.
void BM_MatchStereo(benchmark::State& state) {
  if (!NeedFrames(state)) return;
  const OrbExtractor extractor;
  struct Pair {
    FeatureSet left, right;
    ImagePyramid left_pyramid, right_pyramid;
  };
  std::vector<Pair> pairs;
  for (size_t k = 0; k < Frames().size(); k += 16) {
    const cv::Mat& left = Frames()[k];
    cv::Mat right;
    cv::warpAffine(left, right, cv::Matx23d(1, 0, -20.3, 0, 1, 0), left.size(), cv::INTER_LINEAR,
                   cv::BORDER_REFLECT_101);
    Pair p;
    p.left = extractor.Extract(left, {}, &p.left_pyramid);
    p.right = extractor.Extract(right, {}, &p.right_pyramid);
    pairs.push_back(std::move(p));
  }
  StereoRig rig;
  rig.left.width = Frames()[0].cols;
  rig.left.height = Frames()[0].rows;
  rig.left.fx = rig.left.fy = 707.0912;
  rig.left.cx = 601.8873;
  rig.left.cy = 183.1104;
  rig.baseline = 0.537;
  FrameTimer timer;
  size_t i = 0, matched = 0;
  for (auto _ : state) {
    const Pair& p = pairs[i++ % pairs.size()];
    timer.Start();
    StereoMatches m = MatchStereo(p.left, p.right, p.left_pyramid, p.right_pyramid, rig);
    timer.Stop();
    matched += static_cast<size_t>(m.num_matched);
  }
  timer.Report(state);
  state.counters["matched"] = static_cast<double>(matched) / static_cast<double>(state.iterations());
}
BENCHMARK(BM_MatchStereo)->Iterations(200)->Unit(benchmark::kMillisecond)->UseRealTime();

// Bag of words: transform 2000 descriptors, and query a database of 1000 keyframes.
const Vocabulary& BenchVocabulary() {
  static const Vocabulary vocabulary = [] {
    const std::filesystem::path path = DefaultVocabularyPath();
    if (std::filesystem::exists(path)) return Vocabulary::Load(path);
    OrbOptions orb;
    orb.num_features = 1000;
    const OrbExtractor extractor(orb);
    std::vector<std::vector<Descriptor>> images;
    for (int i = 0; i < 100; ++i)
      images.push_back(extractor.Extract(MakeSyntheticTrainingImage(1000 + i)).descriptors);
    VocabularyTrainingOptions options;
    return Vocabulary::Train(images, options);
  }();
  return vocabulary;
}

void BM_BowTransform(benchmark::State& state) {
  if (!NeedFrames(state)) return;
  const Vocabulary& vocabulary = BenchVocabulary();
  const OrbExtractor extractor;
  std::vector<FeatureSet> sets;
  for (size_t k = 0; k < Frames().size(); k += 10) sets.push_back(extractor.Extract(Frames()[k]));
  FrameTimer timer;
  size_t i = 0;
  for (auto _ : state) {
    BowVector bow;
    FeatureVector fv;
    timer.Start();
    vocabulary.Transform(sets[i++ % sets.size()].descriptors, &bow, &fv);
    timer.Stop();
    benchmark::DoNotOptimize(bow);
  }
  timer.Report(state);
  state.counters["words"] = static_cast<double>(vocabulary.size());
}
BENCHMARK(BM_BowTransform)->Iterations(200)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DatabaseQuery(benchmark::State& state) {
  if (!NeedFrames(state)) return;
  const Vocabulary& vocabulary = BenchVocabulary();
  const OrbExtractor extractor;
  std::vector<BowVector> bows;
  for (const cv::Mat& frame : Frames())
    bows.push_back(vocabulary.Transform(extractor.Extract(frame).descriptors));
  KeyFrameDatabase database(vocabulary.size());
  const int keyframes = static_cast<int>(state.range(0));
  for (int k = 0; k < keyframes; ++k)
    database.Add(static_cast<std::uint64_t>(k), bows[static_cast<size_t>(k) % bows.size()]);
  FrameTimer timer;
  size_t i = 0;
  for (auto _ : state) {
    timer.Start();
    auto results = database.Query(bows[i++ % bows.size()]);
    timer.Stop();
    benchmark::DoNotOptimize(results);
  }
  timer.Report(state);
}
BENCHMARK(BM_DatabaseQuery)
    ->ArgNames({"keyframes"})
    ->Arg(1000)
    ->Iterations(200)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace semslam

BENCHMARK_MAIN();
