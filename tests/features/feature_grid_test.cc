#include "semslam/features/feature_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "semslam/core/error.h"

namespace semslam {
namespace {

FeatureSet RandomFeatures(int n, std::mt19937& rng, float width, float height, float outside = 0.0f) {
  FeatureSet f;
  f.image_width = static_cast<int>(width);
  f.image_height = static_cast<int>(height);
  f.pyramid = PyramidGeometry::Make(8, 1.2f);
  std::uniform_real_distribution<float> ux(-outside, width + outside), uy(-outside, height + outside);
  std::uniform_int_distribution<int> level(0, 7);
  for (int i = 0; i < n; ++i) {
    Keypoint kp;
    kp.pixel = {ux(rng), uy(rng)};
    kp.level = level(rng);
    f.keypoints.push_back(kp);
    f.descriptors.push_back({});
  }
  return f;
}

std::vector<int> BruteForce(const FeatureSet& f, float x, float y, float r, int min_level, int max_level) {
  std::vector<int> out;
  for (size_t i = 0; i < f.size(); ++i) {
    const auto& kp = f.keypoints[i];
    if (min_level >= 0 && kp.level < min_level) continue;
    if (max_level >= 0 && kp.level > max_level) continue;
    if (std::abs(kp.pixel.x() - x) > r || std::abs(kp.pixel.y() - y) > r) continue;
    out.push_back(static_cast<int>(i));
  }
  return out;
}

TEST(FeatureGrid, AreaQueriesEqualBruteForce) {
  std::mt19937 rng(42);
  // Some keypoints outside the bounds (undistorted keypoints can be) must still be found.
  const FeatureSet f = RandomFeatures(3000, rng, 1241, 376, 20.0f);
  const FeatureGrid grid(f, 0, 0, 1241, 376);
  EXPECT_EQ(grid.cols(), 64);
  EXPECT_EQ(grid.rows(), 48);
  std::uniform_real_distribution<float> ux(-50, 1290), uy(-50, 420), ur(0, 120);
  std::uniform_int_distribution<int> level(-1, 7);
  std::vector<int> reused;
  for (int q = 0; q < 2000; ++q) {
    const float x = ux(rng), y = uy(rng), r = ur(rng);
    int lo = level(rng), hi = level(rng);
    if (hi >= 0 && lo > hi) std::swap(lo, hi);
    const auto expected = BruteForce(f, x, y, r, lo, hi);
    EXPECT_EQ(grid.FeaturesInArea(x, y, r, lo, hi), expected)
        << x << " " << y << " " << r << " " << lo << " " << hi;
    grid.FeaturesInArea(x, y, r, lo, hi, reused);
    EXPECT_EQ(reused, expected);
  }
}

TEST(FeatureGrid, EdgeCases) {
  FeatureSet f;
  f.image_width = 100;
  f.image_height = 50;
  const FeatureGrid empty(f);
  EXPECT_TRUE(empty.empty());
  EXPECT_TRUE(empty.FeaturesInArea(10, 10, 100).empty());
  const FeatureGrid default_grid;
  EXPECT_TRUE(default_grid.FeaturesInArea(10, 10, 100).empty());
  Keypoint kp;
  kp.pixel = {10.0f, 10.0f};
  f.keypoints.push_back(kp);
  f.descriptors.push_back({});
  const FeatureGrid one(f);
  EXPECT_EQ(one.FeaturesInArea(10, 10, 0), std::vector<int>{0});  // radius 0: the exact point
  EXPECT_EQ(one.FeaturesInArea(12, 10, 2), std::vector<int>{0});  // on the window's edge
  EXPECT_TRUE(one.FeaturesInArea(12.1f, 10, 2).empty());
  EXPECT_TRUE(one.FeaturesInArea(10, 10, -1).empty());
  EXPECT_TRUE(one.FeaturesInArea(NAN, 10, 5).empty());
  EXPECT_THROW(FeatureGrid(f, 0, 0, 0, 10), InvalidArgument);
}

}  // namespace
}  // namespace semslam
