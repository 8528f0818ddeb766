// Semantics benchmarks: label fusion per keyframe (bar: <= 50 us for 1000 observed points; the paper's data
// association took 500 us), per-keypoint sampling, turning network scores into distributions, the noise
// model, ENet at its native 1024x512, and ESPNetv2 and SINet at several KITTI input sizes, with 2 OpenCV threads
// (needs ../shared/data).
//   build/<preset>/bench/semantics_bench [--benchmark_filter=Fuse]

#include <benchmark/benchmark.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/semantics/dnn_segmenter.h"
#include "semslam/semantics/label_fusion.h"
#include "semslam/semantics/label_image_segmenter.h"
#include "semslam/semantics/model_card.h"
#include "semslam/semantics/segmentation.h"
#include "support/kitti_camera.h"

namespace semslam {
namespace {

const std::filesystem::path kSharedData = SEMSLAM_SHARED_DATA_DIR;

// A segmentation like ENet's on a KITTI frame: 19 log-probabilities per pixel at 1024x512, over a 1241x376
// image.
Segmentation ProbabilitySegmentation(std::mt19937& rng) {
  std::vector<cv::Mat> planes(20);
  for (cv::Mat& p : planes) {
    p.create(512, 1024, CV_32FC1);
    cv::randn(p, 0.0, 2.0);
  }
  std::vector<std::uint8_t> mapping = {kNoLabel};
  for (int c = 0; c < kNumClasses; ++c) mapping.push_back(static_cast<std::uint8_t>(c));
  (void)rng;
  return SegmentationFromScores(planes, ScoreKind::kLogits, mapping, cv::Size(1241, 376));
}

Segmentation LabelSegmentation() {
  cv::Mat labels(376, 1241, CV_8UC1);
  cv::randu(labels, 0, kNumClasses);
  return Segmentation::FromLabels(labels, labels.size(), 0.8f);
}

// `n` world points in front of a keyframe, all projecting into the image, and the keyframe's pose.
struct Scene {
  Rigid3d camera_from_world;
  std::vector<Eigen::Vector3d> points;
  std::vector<LabelDistribution> distributions;
  std::vector<PointObservation> observations;
};

Scene MakeScene(int n, const PinholeCamera& camera, std::mt19937& rng) {
  Scene scene;
  const Rigid3d world_from_camera(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY())),
                                  Eigen::Vector3d(5, 0.2, 40));
  scene.camera_from_world = world_from_camera.Inverse();
  std::uniform_real_distribution<double> u(0, camera.width - 1), v(0, camera.height - 1), depth(2, 60);
  for (int i = 0; i < n; ++i) {
    scene.points.push_back(world_from_camera *
                           camera.UnprojectDepth(Eigen::Vector2d(u(rng), v(rng)), depth(rng)));
  }
  scene.distributions.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i)
    scene.observations.push_back(
        {scene.points[static_cast<size_t>(i)], &scene.distributions[static_cast<size_t>(i)]});
  return scene;
}

void FuseKeyframe(benchmark::State& state, const Segmentation& segmentation) {
  std::mt19937 rng(1);
  const PinholeCamera camera = KittiCamera();
  Scene scene = MakeScene(static_cast<int>(state.range(0)), camera, rng);
  for (auto _ : state) {
    const FusionStats stats =
        FuseKeyframeObservations(segmentation, scene.camera_from_world, camera, scene.observations);
    benchmark::DoNotOptimize(stats);
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}

void BM_FuseKeyframe_Probabilities(benchmark::State& state) {
  std::mt19937 rng(2);
  static const Segmentation segmentation = ProbabilitySegmentation(rng);
  FuseKeyframe(state, segmentation);
}
BENCHMARK(BM_FuseKeyframe_Probabilities)->Arg(1000)->Arg(3000);

void BM_FuseKeyframe_Labels(benchmark::State& state) {
  static const Segmentation segmentation = LabelSegmentation();
  FuseKeyframe(state, segmentation);
}
BENCHMARK(BM_FuseKeyframe_Labels)->Arg(1000)->Arg(3000);

void BM_FuseKeyframe_Compacted(benchmark::State& state) {
  std::mt19937 rng(3);
  static const Segmentation segmentation = ProbabilitySegmentation(rng).Compacted();
  FuseKeyframe(state, segmentation);
}
BENCHMARK(BM_FuseKeyframe_Compacted)->Arg(1000);

void BM_SampleAtKeypoints(benchmark::State& state) {
  std::mt19937 rng(4);
  static const Segmentation segmentation = ProbabilitySegmentation(rng);
  std::uniform_real_distribution<float> u(0, 1240), v(0, 375);
  std::vector<Eigen::Vector2f> pixels(static_cast<size_t>(state.range(0)));
  for (auto& p : pixels) p = Eigen::Vector2f(u(rng), v(rng));
  std::vector<float> rows;
  for (auto _ : state) benchmark::DoNotOptimize(SampleAtPixels(segmentation, pixels, &rows));
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_SampleAtKeypoints)->Arg(2000);

void BM_LabelDistributionFuse(benchmark::State& state) {
  LabelDistribution d;
  const ClassLogProbs observation = ConfusionLogProbs(3, 0.8f);
  for (auto _ : state) {
    d.Fuse(observation);
    benchmark::DoNotOptimize(d);
  }
}
BENCHMARK(BM_LabelDistributionFuse);

// What the network's 20x512x1024 logits cost to turn into 19 log-probabilities per pixel.
void BM_SegmentationFromScores_Enet(benchmark::State& state) {
  std::vector<cv::Mat> planes(20);
  for (cv::Mat& p : planes) {
    p.create(512, 1024, CV_32FC1);
    cv::randn(p, 0.0, 2.0);
  }
  std::vector<std::uint8_t> mapping = {kNoLabel};
  for (int c = 0; c < kNumClasses; ++c) mapping.push_back(static_cast<std::uint8_t>(c));
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        SegmentationFromScores(planes, ScoreKind::kLogits, mapping, cv::Size(1241, 376)));
  }
}
BENCHMARK(BM_SegmentationFromScores_Enet)->Unit(benchmark::kMillisecond);

void BM_LabelNoise_Kitti(benchmark::State& state) {
  cv::Mat truth(376, 1241, CV_8UC1, cv::Scalar(2));
  truth.rowRange(200, 376).setTo(0);
  LabelNoiseOptions options;
  std::uint64_t seed = 0;
  for (auto _ : state) benchmark::DoNotOptimize(AddLabelNoise(truth, options, ++seed));
}
BENCHMARK(BM_LabelNoise_Kitti)->Unit(benchmark::kMillisecond);

// ENet at 1024x512 on a KITTI 07 frame, 2 OpenCV threads.
void BM_Enet_1024x512_2threads(benchmark::State& state) {
  const auto weights = kSharedData / "enet_cityscapes_torch/enet-model.net";
  const auto frame = kSharedData / "kitti_odom_07_3dv/sequences/07/image_0/000050.png";
  if (!std::filesystem::exists(weights) || !std::filesystem::exists(frame)) {
    state.SkipWithError("../shared/data (ENet weights, KITTI 07) missing");
    return;
  }
  DnnSegmenter::Options options;
  options.threads = 2;
  DnnSegmenter segmenter(EnetCityscapesCard(weights), options);
  const cv::Mat image = cv::imread(frame.string(), cv::IMREAD_GRAYSCALE);
  benchmark::DoNotOptimize(segmenter.Segment(image));  // warm-up: the first pass allocates
  for (auto _ : state) benchmark::DoNotOptimize(segmenter.Segment(image));
}
BENCHMARK(BM_Enet_1024x512_2threads)->Unit(benchmark::kMillisecond)->Iterations(5)->UseRealTime();

// ESPNetv2 and SINet (our C++ networks with their published Cityscapes weights) on a KITTI 07 frame, 2 OpenCV
// threads, at network input width range(0) (the frame is scaled to it, aspect ratio kept): the whole
// Segment() call, preprocessing and the 19-class distribution included.
void SegmentKittiFrame(benchmark::State& state, const ModelCard& card) {
  const auto frame = kSharedData / "kitti_odom_07_3dv/sequences/07/image_0/000050.png";
  if (!std::filesystem::exists(card.file) || !std::filesystem::exists(frame)) {
    state.SkipWithError("../shared/data (segmentation weights, KITTI 07) missing");
    return;
  }
  DnnSegmenter::Options options;
  options.threads = 2;
  DnnSegmenter segmenter(card, options);
  const cv::Mat image = cv::imread(frame.string(), cv::IMREAD_GRAYSCALE);
  const cv::Size input = segmenter.NetworkInputSize(image.size());
  benchmark::DoNotOptimize(segmenter.Segment(image));  // warm-up
  for (auto _ : state) benchmark::DoNotOptimize(segmenter.Segment(image));
  state.SetLabel(std::to_string(input.width) + "x" + std::to_string(input.height));
}
void BM_EspNetV2_Kitti_2threads(benchmark::State& state) {
  SegmentKittiFrame(state, EspNetV2CityscapesCard(kSharedData / "segmentation_weights/espnetv2_s_2.0_city_1024x512.pth",
                                                  static_cast<int>(state.range(0))));
}
BENCHMARK(BM_EspNetV2_Kitti_2threads)
    ->Arg(512)->Arg(768)->Arg(1024)->Arg(1248)->Unit(benchmark::kMillisecond)->Iterations(5)->UseRealTime();
void BM_SiNet_Kitti_2threads(benchmark::State& state) {
  SegmentKittiFrame(state, SiNetCityscapesCard(kSharedData / "segmentation_weights/sinet_cityscapes.pth",
                                               static_cast<int>(state.range(0))));
}
BENCHMARK(BM_SiNet_Kitti_2threads)
    ->Arg(768)->Arg(1024)->Arg(1280)->Arg(1536)->Unit(benchmark::kMillisecond)->Iterations(5)->UseRealTime();

}  // namespace
}  // namespace semslam

BENCHMARK_MAIN();
