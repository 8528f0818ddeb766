#include "semslam/features/matching.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "semslam/core/error.h"
#include "semslam/features/orb_extractor.h"
#include "test_images.h"

namespace semslam {
namespace {

TEST(BestTwo, KeepsTheTwoSmallestAndTheRatioTest) {
  BestTwo b;
  EXPECT_FALSE(b.found());
  b.Offer(3, 40);
  EXPECT_TRUE(b.PassesRatio(0.5f));  // no second candidate
  b.Offer(5, 20);
  b.Offer(7, 30);
  b.Offer(9, 50);
  EXPECT_EQ(b.best_index, 5);
  EXPECT_EQ(b.best, 20);
  EXPECT_EQ(b.second, 30);
  EXPECT_TRUE(b.PassesRatio(0.7f));   // 20 < 21
  EXPECT_FALSE(b.PassesRatio(0.6f));  // 20 >= 18
  std::vector<Descriptor> d(3, Descriptor{});
  d[1][0] = 0xFF;  // 8 bits from the query
  d[2][0] = 0x1;   // 1 bit
  const BestTwo c = FindBestTwo(Descriptor{}, std::vector<int>{1, 2}, d);
  EXPECT_EQ(c.best_index, 2);
  EXPECT_EQ(c.best, 1);
  EXPECT_EQ(c.second, 8);
}

TEST(RotationHistogram, KeepsTheThreeDominantBins) {
  RotationHistogram h;  // 30 bins of 12 degrees
  EXPECT_EQ(h.BinOf(0.0f), 0);
  EXPECT_EQ(h.BinOf(11.9f), 0);
  EXPECT_EQ(h.BinOf(12.0f), 1);
  EXPECT_EQ(h.BinOf(-1.0f), 29);
  EXPECT_EQ(h.BinOf(725.0f), 0);
  int id = 0;
  for (int i = 0; i < 50; ++i) h.Add(3.0f, id++);   // bin 0: ids 0..49
  for (int i = 0; i < 20; ++i) h.Add(-5.0f, id++);  // bin 29: ids 50..69
  for (int i = 0; i < 6; ++i) h.Add(14.0f, id++);   // bin 1: ids 70..75 (>= 10 % of 50)
  for (int i = 0; i < 4; ++i) h.Add(100.0f, id++);  // bin 8: ids 76..79 (4th largest)
  EXPECT_EQ(h.DominantBins(), (std::vector<int>{0, 29, 1}));
  EXPECT_EQ(h.Inconsistent(), (std::vector<int>{76, 77, 78, 79}));
  EXPECT_EQ(h.Consistent().size(), 76u);
  // A third bin below 10 % of the largest is not dominant.
  RotationHistogram g;
  for (int i = 0; i < 100; ++i) g.Add(0.0f, i);
  for (int i = 0; i < 9; ++i) g.Add(180.0f, 100 + i);
  EXPECT_EQ(g.DominantBins(), std::vector<int>{0});
  EXPECT_EQ(g.Inconsistent().size(), 9u);
  EXPECT_TRUE(RotationHistogram().Inconsistent().empty());
}

TEST(MatchForInitialization, FindsTheShiftAndRejectsInconsistentRotations) {
  const cv::Mat image = testing::SyntheticStreetSizedImage(13);
  cv::Mat shifted;
  const cv::Matx23d shift(1, 0, 6, 0, 1, -3);
  cv::warpAffine(image, shifted, shift, image.size(), cv::INTER_NEAREST, cv::BORDER_REFLECT_101);
  const OrbExtractor extractor;
  const FeatureSet f1 = extractor.Extract(image);
  const FeatureSet f2 = extractor.Extract(shifted);
  std::vector<Eigen::Vector2f> prior;
  for (const auto& kp : f1.keypoints) prior.push_back(kp.pixel);
  const std::vector<int> m = MatchForInitialization(f1, f2, prior, 20.0f);
  ASSERT_EQ(m.size(), f1.size());
  int matched = 0, right = 0;
  std::vector<int> used(f2.size(), 0);
  for (size_t i = 0; i < m.size(); ++i) {
    if (m[i] < 0) continue;
    EXPECT_EQ(f1.keypoints[i].level, 0);
    ++matched;
    ++used[static_cast<size_t>(m[i])];
    const Eigen::Vector2f d = f2.keypoints[static_cast<size_t>(m[i])].pixel - f1.keypoints[i].pixel;
    right += std::abs(d.x() - 6.0f) < 1.0f && std::abs(d.y() + 3.0f) < 1.0f;
  }
  EXPECT_GT(matched, 300);
  EXPECT_GT(right, 0.97 * matched);
  for (const int u : used) EXPECT_LE(u, 1);  // one to one

  // Flip the orientation of some f2 keypoints: their matches fall outside the dominant bins.
  FeatureSet f2_bad = f2;
  std::vector<int> flipped;
  for (size_t i = 0; i < m.size() && flipped.size() < 20; ++i) {
    if (m[i] < 0) continue;
    auto& a = f2_bad.keypoints[static_cast<size_t>(m[i])].angle_deg;
    a = std::fmod(a + 150.0f, 360.0f);
    flipped.push_back(static_cast<int>(i));
  }
  const std::vector<int> m2 = MatchForInitialization(f1, f2_bad, prior, 20.0f);
  for (const int i : flipped) EXPECT_EQ(m2[static_cast<size_t>(i)], -1);

  EXPECT_THROW(MatchForInitialization(f1, f2, {}, 20.0f), InvalidArgument);
}

TEST(MatchBruteForce, RatioAndMutualChecks) {
  std::mt19937_64 rng(5);
  FeatureSet a, b;
  for (int i = 0; i < 50; ++i) {
    Descriptor d = {rng(), rng(), rng(), rng()};
    a.keypoints.emplace_back();
    a.descriptors.push_back(d);
    d[0] ^= 0x7;  // 3 bits off
    b.keypoints.emplace_back();
    b.descriptors.push_back(d);
  }
  std::reverse(b.descriptors.begin(), b.descriptors.end());
  const auto m = MatchBruteForce(a, b);
  for (int i = 0; i < 50; ++i) EXPECT_EQ(m[static_cast<size_t>(i)], 49 - i);
  // Two equally good candidates fail the ratio test.
  b.descriptors.push_back(b.descriptors[0]);
  b.keypoints.emplace_back();
  EXPECT_EQ(MatchBruteForce(a, b)[49], -1);
}

}  // namespace
}  // namespace semslam
