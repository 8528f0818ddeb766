// Rendering: deterministic bytes on any number of threads, labels and depth consistent with the scene, the
// stereo geometry of the right image, and images on which our ORB extractor finds and matches real corners.

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>

#include "semslam/features/matching.h"
#include "semslam/features/orb_extractor.h"
#include "semslam/semantics/class_table.h"
#include "semslam/sim/pattern_filter.h"
#include "semslam/sim/raycaster.h"
#include "semslam/sim/renderer.h"
#include "semslam/sim/synthetic_city.h"
#include "semslam/sim/texture.h"

namespace semslam::sim {
namespace {

// Half the KITTI resolution and focal length, for the tests that do not need full frames.
SynthOptions HalfSize(std::uint64_t seed = 1, int frames = 400) {
  SynthOptions o = PresetOptions("default");
  o.city.seed = seed;
  o.route.frames = frames;
  o.camera.width = 620;
  o.camera.height = 188;
  o.camera.focal = 718.856 / 2;
  return o;
}

const SyntheticCity& HalfCity() {
  static const SyntheticCity city(HalfSize());
  return city;
}

const SyntheticCity& FullCity() {
  static const SyntheticCity city([] {
    SynthOptions o = PresetOptions("default");
    o.route.frames = 400;
    return o;
  }());
  return city;
}

bool Same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

TEST(Texture, FilteredPatternsAverageOut) {
  // A pulse train seen through a wide footprint becomes its duty cycle, through a narrow one stays sharp.
  EXPECT_NEAR(PulseCoverage(0.37f, 1.0f, 0.25f, 10.0f), 0.25f, 1e-3f);
  EXPECT_NEAR(PulseCoverage(0.1f, 1.0f, 0.25f, 0.01f), 1.0f, 1e-5f);
  EXPECT_NEAR(PulseCoverage(0.6f, 1.0f, 0.25f, 0.01f), 0.0f, 1e-5f);
  EXPECT_NEAR(PulseCoverage(0.25f, 1.0f, 0.25f, 0.1f), 0.5f, 1e-3f);
  EXPECT_NEAR(IntervalCoverage(1.0f, 0.0f, 1.0f, 0.2f), 0.5f, 1e-5f);
  // Noise fades to zero when its finest octave is below two pixels.
  EXPECT_EQ(FilteredNoise2(3.3f, 7.1f, 5u, 4.0f, 4, 1.0f), 0.0f);
  float spread = 0;
  for (int i = 0; i < 100; ++i)
    spread = std::max(spread, std::abs(FilteredNoise2(i * 0.37f, i * 0.11f, 5u, 1.0f, 4, 0.001f)));
  EXPECT_GT(spread, 0.3f);
  EXPECT_LE(spread, 1.7f);
}

TEST(Render, DeterministicOnAnyNumberOfThreads) {
  const SyntheticCity& sim = HalfCity();
  const RenderedFrame a = sim.Render(37);
  const RenderedFrame b = sim.Render(37);
  SynthOptions serial_options = HalfSize();
  serial_options.render.parallel = false;
  const SyntheticCity serial(serial_options);
  const RenderedFrame c = serial.Render(37);
  for (const RenderedFrame* x : {&b, &c}) {
    EXPECT_TRUE(Same(a.left, x->left));
    EXPECT_TRUE(Same(a.right, x->right));
    EXPECT_TRUE(Same(a.labels, x->labels));
    EXPECT_TRUE(Same(a.depth, x->depth));
  }
  EXPECT_EQ(a.left.type(), CV_8UC1);
  EXPECT_EQ(a.labels.type(), CV_8UC1);
  EXPECT_EQ(a.depth.type(), CV_16UC1);
  EXPECT_EQ(a.left.cols, 620);
  EXPECT_EQ(a.left.rows, 188);
  // Another frame, another seed: other images.
  EXPECT_FALSE(Same(a.left, sim.Render(38, kRenderLeft).left));
  const SyntheticCity other(HalfSize(2));
  EXPECT_GT(cv::norm(a.left, other.Render(37, kRenderLeft).left, cv::NORM_L1) / a.left.total(), 10.0);
}

TEST(Render, ColumnCastingMatchesOneRayPerPixel) {
  const SyntheticCity& sim = HalfCity();
  SynthOptions per_ray_options = HalfSize();
  per_ray_options.render.column_casting = false;
  const SyntheticCity per_ray(per_ray_options);
  for (const size_t frame : {10u, 115u, 300u}) {
    const RenderedFrame a = sim.Render(frame, kRenderLeft | kRenderLabels | kRenderDepth);
    const RenderedFrame b = per_ray.Render(frame, kRenderLeft | kRenderLabels | kRenderDepth);
    int same_label = 0, close_depth = 0, close_grey = 0;
    const int total = static_cast<int>(a.labels.total());
    for (int v = 0; v < a.labels.rows; ++v) {
      for (int u = 0; u < a.labels.cols; ++u) {
        same_label += a.labels.at<std::uint8_t>(v, u) == b.labels.at<std::uint8_t>(v, u);
        close_depth += std::abs(a.depth.at<std::uint16_t>(v, u) - b.depth.at<std::uint16_t>(v, u)) <= 2;
        close_grey += std::abs(a.left.at<std::uint8_t>(v, u) - b.left.at<std::uint8_t>(v, u)) <= 2;
      }
    }
    EXPECT_GT(same_label, total - total / 500) << frame;
    EXPECT_GT(close_depth, total - total / 200) << frame;
    EXPECT_GT(close_grey, total - total / 100) << frame;
  }
}

TEST(Render, LabelsAndDepthMatchTheScene) {
  const SyntheticCity& sim = HalfCity();
  const PinholeCamera& cam = sim.rig().left;
  int checked = 0, agree = 0, sky = 0;
  std::vector<int> seen(kNumClasses, 0);
  for (const size_t frame : {5u, 120u, 260u}) {
    const RenderedFrame r = sim.Render(frame, kRenderLabels | kRenderDepth);
    const Rigid3d world_from_camera = sim.WorldFromCamera(frame);
    for (int v = 1; v < cam.height; v += 3) {
      for (int u = 1; u < cam.width; u += 3) {
        const int label = r.labels.at<std::uint8_t>(v, u);
        const int depth = r.depth.at<std::uint16_t>(v, u);
        ASSERT_TRUE(IsValidTrainId(label));
        ++seen[static_cast<size_t>(label)];
        if (label == TrainId(SemanticClass::kSky)) {
          EXPECT_EQ(depth, 0);
          ++sky;
          continue;
        }
        ASSERT_GT(depth, 0);
        if (depth == 65535) continue;
        const Eigen::Vector3d point =
            world_from_camera * cam.UnprojectDepth(Eigen::Vector2d(u, v), depth / 256.0);
        const SurfaceClass truth = sim.ClassAt(point);
        ++checked;
        if (truth.label == label && truth.distance < 0.02) ++agree;
      }
    }
  }
  EXPECT_GT(sky, 100);
  EXPECT_GT(checked, 20000);
  EXPECT_GT(static_cast<double>(agree) / checked, 0.985) << agree << " of " << checked;
  for (const SemanticClass c : {SemanticClass::kRoad, SemanticClass::kSidewalk, SemanticClass::kBuilding,
                                SemanticClass::kPole, SemanticClass::kVegetation, SemanticClass::kCar}) {
    EXPECT_GT(seen[static_cast<size_t>(TrainId(c))], 0) << ClassName(TrainId(c));
  }
}

TEST(Render, RightImageIsTheLeftShiftedByTheDisparity) {
  // For pixels of the left image, the right image shows the same grey (up to noise and occlusions) at
  // u - fx * baseline / z.
  const SyntheticCity& sim = HalfCity();
  const RenderedFrame r = sim.Render(60);
  const StereoRig& rig = sim.rig();
  int compared = 0, close = 0;
  for (int v = 100; v < rig.left.height - 2; v += 2) {
    for (int u = 40; u < rig.left.width - 2; u += 2) {
      const int d = r.depth.at<std::uint16_t>(v, u);
      if (d == 0 || d == 65535) continue;
      const double z = d / 256.0;
      const int ur = static_cast<int>(std::lround(u - rig.DisparityFromDepth(z)));
      if (ur < 0) continue;
      ++compared;
      close += std::abs(static_cast<int>(r.left.at<std::uint8_t>(v, u)) -
                        static_cast<int>(r.right.at<std::uint8_t>(v, ur))) <= 12;
    }
  }
  EXPECT_GT(compared, 5000);
  EXPECT_GT(static_cast<double>(close) / compared, 0.85);
}

TEST(Render, OrbFindsAndMatchesCornersOnFullFrames) {
  const SyntheticCity& sim = FullCity();
  OrbOptions options;
  options.num_features = 2000;
  const OrbExtractor orb(options);
  for (const size_t frame : {30u, 200u}) {
    const RenderedFrame a = sim.Render(frame, kRenderLeft);
    const RenderedFrame b = sim.Render(frame + 1, kRenderLeft);
    const FeatureSet fa = orb.Extract(a.left);
    const FeatureSet fb = orb.Extract(b.left);
    EXPECT_GE(fa.size(), 1500u) << frame;
    // Spread: features in every sixth of the width, and in the lower and the upper half.
    std::vector<int> columns(6, 0);
    int upper = 0, lower = 0;
    for (size_t i = 0; i < fa.size(); ++i) {
      const Eigen::Vector2f& p = fa.keypoints[i].pixel;
      ++columns[std::min<size_t>(5, static_cast<size_t>(p.x() / a.left.cols * 6))];
      (p.y() < a.left.rows / 2 ? upper : lower)++;
    }
    for (const int c : columns) EXPECT_GE(c, 60) << frame;
    EXPECT_GE(upper, 300) << frame;
    EXPECT_GE(lower, 300) << frame;
    // Consecutive frames share many features.
    const std::vector<int> matches = MatchBruteForce(fa, fb);
    const int matched =
        static_cast<int>(std::count_if(matches.begin(), matches.end(), [](int m) { return m >= 0; }));
    EXPECT_GE(matched, 300) << frame;
  }
}

}  // namespace
}  // namespace semslam::sim
