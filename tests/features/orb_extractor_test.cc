#include "semslam/features/orb_extractor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <thread>

#include "semslam/core/error.h"
#include "semslam/features/matching.h"
#include "semslam/features/orb_descriptor.h"
#include "support/test_support.h"
#include "test_images.h"

namespace semslam {
namespace {

using testing::Kitti07Frame;
using testing::SyntheticStreetSizedImage;

template <typename T>
T Median(std::vector<T> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

float AngleDifference(float a, float b) {
  float d = std::fmod(a - b, 360.0f);
  if (d < -180.0f) d += 360.0f;
  if (d > 180.0f) d -= 360.0f;
  return d;
}

TEST(OrbOptions, DefaultsAreValidAndBadValuesAreRejected) {
  OrbOptions o;
  EXPECT_NO_THROW(o.Check());
  EXPECT_EQ(o.num_features, 2000);
  EXPECT_EQ(o.num_levels, 8);
  EXPECT_FLOAT_EQ(o.scale_factor, 1.2f);
  EXPECT_EQ(o.initial_fast_threshold, 20);
  EXPECT_EQ(o.min_fast_threshold, 7);
  auto bad = [](auto change) {
    OrbOptions b;
    change(b);
    return b;
  };
  EXPECT_THROW(bad([](OrbOptions& b) { b.num_features = 0; }).Check(), InvalidArgument);
  EXPECT_THROW(bad([](OrbOptions& b) { b.num_levels = 0; }).Check(), InvalidArgument);
  EXPECT_THROW(bad([](OrbOptions& b) { b.scale_factor = 1.0f; }).Check(), InvalidArgument);
  EXPECT_THROW(bad([](OrbOptions& b) { b.min_fast_threshold = 30; }).Check(), InvalidArgument);
  EXPECT_THROW(bad([](OrbOptions& b) { b.edge_threshold = 10; }).Check(), InvalidArgument);
  EXPECT_THROW(OrbExtractor(bad([](OrbOptions& b) { b.cell_size = 2; })), InvalidArgument);
}

TEST(OrbExtractor, LevelBudgetsFollowTheLevelShareExponent) {
  for (const double exponent : {1.0, 2.0}) {
    OrbOptions options;
    options.level_share_exponent = exponent;
    const OrbExtractor extractor(options);
    const std::vector<int> budget = extractor.LevelBudgets();
    ASSERT_EQ(budget.size(), 8u);
    EXPECT_EQ(std::accumulate(budget.begin(), budget.end(), 0), 2000);
    for (size_t l = 0; l + 2 < budget.size(); ++l) {
      EXPECT_NEAR(static_cast<double>(budget[l]) / budget[l + 1], std::pow(1.2, exponent), 0.03)
          << "exponent " << exponent << ", level " << l;
    }
  }
}

TEST(DistributeLevelBudgets, GivesWhatShortLevelsCannotUseToTheOthers) {
  // Enough everywhere: unchanged.
  EXPECT_EQ(DistributeLevelBudgets({50, 30, 20}, {100, 100, 100}), (std::vector<int>{50, 30, 20}));
  // Level 2 has only 5: its 15 go to levels 0 and 1 in proportion 50:30 (9 and 5, +1 by rounding).
  const auto r = DistributeLevelBudgets({50, 30, 20}, {100, 100, 5});
  EXPECT_EQ(r[2], 5);
  EXPECT_EQ(r[0] + r[1], 95);
  EXPECT_GT(r[0], r[1]);
  // Not enough in total: everyone gives all it has.
  EXPECT_EQ(DistributeLevelBudgets({50, 30, 20}, {10, 0, 3}), (std::vector<int>{10, 0, 3}));
  // A level with nothing wanted still takes overflow if it has candidates.
  EXPECT_EQ(DistributeLevelBudgets({10, 0}, {4, 50}), (std::vector<int>{4, 6}));
}

TEST(SelectSpreadOut, EveryCellGetsOneBeforeAnyGetsTwo) {
  // 1000 strong candidates packed in the top-left 10x10 pixels, and one weak candidate per 10x10 cell of a
  // 100x100 area: 100 picks must take every cell's candidate (the packed corner counts as one cell).
  std::vector<CornerCandidate> candidates;
  for (int i = 0; i < 1000; ++i)
    candidates.push_back({static_cast<float>(i % 10), static_cast<float>(i / 100), 100.0f + i});
  for (int cy = 0; cy < 10; ++cy) {
    for (int cx = 0; cx < 10; ++cx) {
      if (cx == 0 && cy == 0) continue;
      candidates.push_back({cx * 10.0f + 5.0f, cy * 10.0f + 5.0f, 1.0f});
    }
  }
  const std::vector<int> chosen = SelectSpreadOut(candidates, 100, 0, 0, 100, 100);
  ASSERT_EQ(chosen.size(), 100u);
  std::vector<int> per_cell(100, 0);
  for (const int i : chosen) {
    const auto& c = candidates[static_cast<size_t>(i)];
    ++per_cell[static_cast<size_t>(static_cast<int>(c.y) / 10 * 10 + static_cast<int>(c.x) / 10)];
  }
  for (int c = 0; c < 100; ++c) EXPECT_EQ(per_cell[static_cast<size_t>(c)], 1) << "cell " << c;
  // The corner cell gave its strongest.
  EXPECT_NE(std::find(chosen.begin(), chosen.end(), 999), chosen.end());
  // Fewer candidates than the budget: all of them.
  EXPECT_EQ(SelectSpreadOut({{1, 1, 1}, {2, 2, 2}}, 5, 0, 0, 10, 10).size(), 2u);
}

// Features of an image in a grid of regions: how many regions have at least `min_count`.
int RegionsWithFeatures(const FeatureSet& f, int cols, int rows, int min_count) {
  std::vector<int> count(static_cast<size_t>(cols * rows), 0);
  for (const auto& kp : f.keypoints) {
    const int cx = std::clamp(static_cast<int>(kp.pixel.x() * cols / f.image_width), 0, cols - 1);
    const int cy = std::clamp(static_cast<int>(kp.pixel.y() * rows / f.image_height), 0, rows - 1);
    ++count[static_cast<size_t>(cy * cols + cx)];
  }
  return static_cast<int>(std::count_if(count.begin(), count.end(), [&](int c) { return c >= min_count; }));
}

void ExpectWellFormed(const FeatureSet& f, const cv::Mat& image, const OrbOptions& options) {
  ASSERT_EQ(f.keypoints.size(), f.descriptors.size());
  EXPECT_EQ(f.image_width, image.cols);
  EXPECT_EQ(f.image_height, image.rows);
  EXPECT_EQ(f.pyramid.num_levels, options.num_levels);
  for (const auto& kp : f.keypoints) {
    EXPECT_GE(kp.level, 0);
    EXPECT_LT(kp.level, options.num_levels);
    // At least edge_threshold level pixels from the border.
    const float margin =
        static_cast<float>(options.edge_threshold) * f.pyramid.scale[static_cast<size_t>(kp.level)] - 2.0f;
    EXPECT_GE(kp.pixel.x(), margin);
    EXPECT_GE(kp.pixel.y(), margin);
    EXPECT_LE(kp.pixel.x(), image.cols - 1 - margin);
    EXPECT_LE(kp.pixel.y(), image.rows - 1 - margin);
    EXPECT_GE(kp.angle_deg, 0.0f);
    EXPECT_LT(kp.angle_deg, 360.0f);
    EXPECT_GT(kp.response, 0.0f);
  }
}

TEST(OrbExtractor, SyntheticImageGetsTheFullCountSpreadOverImageAndLevels) {
  const cv::Mat image = SyntheticStreetSizedImage();
  const OrbOptions options;
  const OrbExtractor extractor(options);
  const FeatureSet f = extractor.Extract(image);
  ExpectWellFormed(f, image, options);
  EXPECT_EQ(f.size(), 2000u);
  std::vector<int> per_level(8, 0);
  for (const auto& kp : f.keypoints) ++per_level[static_cast<size_t>(kp.level)];
  for (int l = 0; l < 8; ++l) EXPECT_GT(per_level[static_cast<size_t>(l)], 10) << "level " << l;
  EXPECT_EQ(RegionsWithFeatures(f, 8, 3, 20), 24);
}

FeatureSet OpenCvOrb(const cv::Mat& image) {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  cv::ORB::create(2000)->detectAndCompute(image, cv::noArray(), keypoints, descriptors);
  FeatureSet f;
  f.image_width = image.cols;
  f.image_height = image.rows;
  for (const auto& kp : keypoints) {
    Keypoint k;
    k.pixel = {kp.pt.x, kp.pt.y};
    f.keypoints.push_back(k);
  }
  return f;
}

TEST(OrbExtractor, KittiFramesGetTheFullCountSpreadOverTheImage) {
  SEMSLAM_REQUIRE_SHARED_DATA(root, "kitti_odom_07_3dv");
  const OrbOptions options;
  const OrbExtractor extractor(options);
  for (const int index : {0, 50, 100, 159}) {
    const cv::Mat image = Kitti07Frame(root, index);
    ASSERT_FALSE(image.empty());
    const FeatureSet f = extractor.Extract(image);
    ExpectWellFormed(f, image, options);
    EXPECT_EQ(f.size(), 2000u) << "frame " << index;
    // 8 x 3 regions of about 155 x 125 pixels: nearly all have features (a white wall or a black shadow may
    // have none at FAST threshold 7), more of them than with OpenCV's ORB, and none hoards them.
    const FeatureSet reference = OpenCvOrb(image);
    EXPECT_GE(RegionsWithFeatures(f, 8, 3, 15), 21) << "frame " << index;
    EXPECT_GE(RegionsWithFeatures(f, 8, 3, 15), RegionsWithFeatures(reference, 8, 3, 15))
        << "frame " << index;
    EXPECT_EQ(RegionsWithFeatures(f, 8, 3, 300), 0) << "frame " << index;
  }
}

TEST(OrbExtractor, IsDeterministicThreadSafeAndTheSameSerialOrParallel) {
  const cv::Mat image = SyntheticStreetSizedImage(3);
  OrbOptions options;
  const OrbExtractor extractor(options);
  const FeatureSet reference = extractor.Extract(image);
  options.parallel = false;
  const FeatureSet serial = OrbExtractor(options).Extract(image);
  ASSERT_EQ(serial.size(), reference.size());
  FeatureSet a, b;
  std::thread ta([&] { a = extractor.Extract(image); });
  std::thread tb([&] { b = extractor.Extract(image); });
  ta.join();
  tb.join();
  for (const FeatureSet* f : std::vector<const FeatureSet*>{&serial, &a, &b}) {
    ASSERT_EQ(f->size(), reference.size());
    for (size_t i = 0; i < reference.size(); ++i) {
      EXPECT_EQ(f->keypoints[i].pixel, reference.keypoints[i].pixel);
      EXPECT_EQ(f->keypoints[i].level, reference.keypoints[i].level);
      EXPECT_EQ(f->keypoints[i].angle_deg, reference.keypoints[i].angle_deg);
      EXPECT_EQ(f->descriptors[i], reference.descriptors[i]);
    }
  }
}

TEST(OrbExtractor, MaskExcludesPixelsAndTheCountIsKept) {
  const cv::Mat image = SyntheticStreetSizedImage(5);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(255));
  mask(cv::Rect(0, 0, 620, image.rows)).setTo(0);  // e.g. a car on the left
  const OrbExtractor extractor;
  const FeatureSet f = extractor.Extract(image, mask);
  // Half the image holds fewer corners than the budget on some levels; the rest is found elsewhere.
  EXPECT_GT(f.size(), 1600u);
  for (const auto& kp : f.keypoints) {
    const int x = static_cast<int>(std::lround(kp.pixel.x())),
              y = static_cast<int>(std::lround(kp.pixel.y()));
    EXPECT_NE(mask.at<std::uint8_t>(y, x), 0) << kp.pixel.transpose();
  }
  EXPECT_THROW(extractor.Extract(image, cv::Mat(10, 10, CV_8UC1)), InvalidArgument);
  EXPECT_THROW(extractor.Extract(cv::Mat()), InvalidArgument);
}

TEST(OrbExtractor, TinyAndBlankImages) {
  const OrbExtractor extractor;
  for (const cv::Size size : {cv::Size(1, 1), cv::Size(20, 20), cv::Size(33, 100), cv::Size(300, 40)}) {
    const cv::Mat image = MakeSyntheticTrainingImage(2, size);
    const FeatureSet f = extractor.Extract(image);
    EXPECT_EQ(f.keypoints.size(), f.descriptors.size());
    for (const auto& kp : f.keypoints) {
      EXPECT_GE(kp.pixel.x(), 15.0f);
      EXPECT_LE(kp.pixel.x(), static_cast<float>(size.width) - 16.0f);
    }
  }
  EXPECT_EQ(extractor.Extract(cv::Mat(376, 1241, CV_8UC1, cv::Scalar(128))).size(), 0u);
}

TEST(OrbExtractor, ColourInputAndPyramidOutput) {
  const cv::Mat grey = SyntheticStreetSizedImage(9);
  cv::Mat colour;
  cv::cvtColor(grey, colour, cv::COLOR_GRAY2BGR);
  const OrbExtractor extractor;
  ImagePyramid pyramid;
  const FeatureSet a = extractor.Extract(colour, {}, &pyramid);
  const FeatureSet b = extractor.Extract(grey);
  EXPECT_EQ(a.size(), b.size());
  ASSERT_EQ(pyramid.num_levels(), 8);
  EXPECT_EQ(pyramid.levels[0].size(), grey.size());
  EXPECT_EQ(pyramid.levels[1].size(), cv::Size(1034, 313));  // round(1241 / 1.2), round(376 / 1.2)
  EXPECT_NEAR(pyramid.ratio_x[7], std::pow(1.2, 7), 0.02);
  // Level coordinates map back and forth.
  EXPECT_NEAR(pyramid.FromLevel0X(pyramid.ToLevel0X(17.0f, 3), 3), 17.0f, 1e-4);
}

// Correspondences of the keypoints of `a` in `b` under the affine map `m` (a -> b): the nearest keypoint of
// b on the same level within 1.5 level pixels of the predicted position.
struct Correspondence {
  size_t ia, ib;
};
std::vector<Correspondence> GeometricCorrespondences(const FeatureSet& a, const FeatureSet& b,
                                                     const cv::Matx23d& m, int level_offset = 0,
                                                     double scale = 1.0) {
  std::vector<Correspondence> out;
  for (size_t i = 0; i < a.size(); ++i) {
    const auto& kp = a.keypoints[i];
    const double x = kp.pixel.x(), y = kp.pixel.y();
    const double px = m(0, 0) * x + m(0, 1) * y + m(0, 2), py = m(1, 0) * x + m(1, 1) * y + m(1, 2);
    const double radius =
        1.5 * b.pyramid.scale[static_cast<size_t>(std::clamp(kp.level - level_offset, 0, 7))] * scale;
    double best = radius;
    int best_j = -1;
    for (size_t j = 0; j < b.size(); ++j) {
      if (b.keypoints[j].level != kp.level - level_offset) continue;
      const double d = std::hypot(b.keypoints[j].pixel.x() - px, b.keypoints[j].pixel.y() - py);
      if (d < best) {
        best = d;
        best_j = static_cast<int>(j);
      }
    }
    if (best_j >= 0) out.push_back({i, static_cast<size_t>(best_j)});
  }
  return out;
}

void ExpectRotationInvariance(const FeatureSet& a, const FeatureSet& b, const cv::Matx23d& a_to_b,
                              double degrees) {
  const auto corr = GeometricCorrespondences(a, b, a_to_b);
  ASSERT_GT(corr.size(), 300u);
  std::vector<float> angle_error;
  std::vector<int> distance, random_distance;
  for (size_t k = 0; k < corr.size(); ++k) {
    const auto& c = corr[k];
    angle_error.push_back(std::abs(AngleDifference(a.keypoints[c.ia].angle_deg - b.keypoints[c.ib].angle_deg,
                                                   static_cast<float>(degrees))));
    distance.push_back(HammingDistance(a.descriptors[c.ia], b.descriptors[c.ib]));
    random_distance.push_back(
        HammingDistance(a.descriptors[c.ia], b.descriptors[corr[(k + 37) % corr.size()].ib]));
  }
  EXPECT_LT(Median(angle_error), 3.0f) << "rotation " << degrees;
  EXPECT_LT(Median(distance), 32) << "rotation " << degrees;
  EXPECT_GT(Median(random_distance), 100) << "rotation " << degrees;
  // Correct correspondences match as nearest neighbours in descriptor space.
  const auto matches = MatchBruteForce(a, b, {});
  int right = 0, total = 0;
  for (const auto& c : corr) {
    if (matches[c.ia] < 0) continue;
    ++total;
    right += matches[c.ia] == static_cast<int>(c.ib);
  }
  EXPECT_GT(right, 0.9 * total) << "rotation " << degrees;
}

TEST(OrbExtractor, RotationInvariance) {
  const cv::Mat image = MakeSyntheticTrainingImage(21, cv::Size(700, 700));
  const OrbExtractor extractor;
  const FeatureSet a = extractor.Extract(image);
  // Exact 90 degree rotation: (x, y) -> (y, W - 1 - x).
  {
    cv::Mat rotated;
    cv::rotate(image, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
    const FeatureSet b = extractor.Extract(rotated);
    ExpectRotationInvariance(a, b, cv::Matx23d(0, 1, 0, -1, 0, image.cols - 1), 90.0);
  }
  // Interpolated rotations about the centre.
  for (const double degrees : {30.0, -45.0, 160.0}) {
    const cv::Mat m = cv::getRotationMatrix2D(cv::Point2f(349.5f, 349.5f), degrees, 1.0);
    cv::Mat rotated;
    cv::warpAffine(image, rotated, m, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
    const FeatureSet b = extractor.Extract(rotated);
    ExpectRotationInvariance(a, b, cv::Matx23d(m.ptr<double>()), degrees);
  }
}

TEST(OrbExtractor, ScaleLevelsFollowTheImageScale) {
  // The image shrunk by 1.2^2: what level l + 2 saw in the original, level l sees in the small one.
  const cv::Mat image = SyntheticStreetSizedImage(11);
  cv::Mat small;
  cv::resize(image, small, cv::Size(), 1.0 / 1.44, 1.0 / 1.44, cv::INTER_AREA);
  const OrbExtractor extractor;
  const FeatureSet a = extractor.Extract(image);
  const FeatureSet b = extractor.Extract(small);
  const double sx = static_cast<double>(small.cols) / image.cols,
               sy = static_cast<double>(small.rows) / image.rows;
  const cv::Matx23d m(sx, 0, 0.5 * sx - 0.5, 0, sy, 0.5 * sy - 0.5);
  // Correspondences at level offset 2 are plentiful and agree in descriptor...
  const auto shifted = GeometricCorrespondences(a, b, m, 2, 1.0);
  ASSERT_GT(shifted.size(), 150u);
  std::vector<int> distance;
  for (const auto& c : shifted) distance.push_back(HammingDistance(a.descriptors[c.ia], b.descriptors[c.ib]));
  EXPECT_LT(Median(distance), 40);
  // ...and more plentiful than at offset 0 (levels not adjusted for scale).
  const auto same = GeometricCorrespondences(a, b, m, 0, 1.0);
  std::vector<int> distance_same;
  for (const auto& c : same)
    distance_same.push_back(HammingDistance(a.descriptors[c.ia], b.descriptors[c.ib]));
  EXPECT_LT(Median(distance), Median(distance_same));
}

TEST(OrbExtractor, RepeatableOnConsecutiveKittiFrames) {
  SEMSLAM_REQUIRE_SHARED_DATA(root, "kitti_odom_07_3dv");
  const OrbExtractor extractor;
  for (const int index : {0, 60, 120}) {
    const FeatureSet a = extractor.Extract(Kitti07Frame(root, index));
    const FeatureSet b = extractor.Extract(Kitti07Frame(root, index + 1));
    const auto matches = MatchBruteForce(a, b, {});
    std::vector<cv::Point2f> pa, pb;
    for (size_t i = 0; i < a.size(); ++i) {
      if (matches[i] < 0) continue;
      pa.emplace_back(a.keypoints[i].pixel.x(), a.keypoints[i].pixel.y());
      pb.emplace_back(b.keypoints[static_cast<size_t>(matches[i])].pixel.x(),
                      b.keypoints[static_cast<size_t>(matches[i])].pixel.y());
    }
    ASSERT_GT(pa.size(), 400u) << "frame " << index;
    cv::Mat inliers;
    cv::findFundamentalMat(pa, pb, cv::FM_RANSAC, 1.0, 0.999, inliers);
    const int n = cv::countNonZero(inliers);
    EXPECT_GT(n, 350) << "frame " << index;
    EXPECT_GT(static_cast<double>(n) / static_cast<double>(pa.size()), 0.65) << "frame " << index;
  }
}

TEST(OrbExtractor, OpenCvPatternOption) {
  const cv::Mat image = MakeSyntheticTrainingImage(21, cv::Size(700, 700));
  OrbOptions options;
  options.pattern = OrbDescriptorPattern::kOpenCv;
  const OrbExtractor extractor(options);
  const FeatureSet a = extractor.Extract(image);
  EXPECT_GT(a.size(), 1900u);
  const FeatureSet ours = OrbExtractor().Extract(image);
  ASSERT_EQ(a.size(), ours.size());
  int same = 0;
  for (size_t i = 0; i < a.size(); ++i) same += a.descriptors[i] == ours.descriptors[i];
  EXPECT_LT(same, 10);
  // Steered too: invariant to rotation.
  cv::Mat rotated;
  cv::rotate(image, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  ExpectRotationInvariance(a, extractor.Extract(rotated), cv::Matx23d(0, 1, 0, -1, 0, image.cols - 1), 90.0);
}

TEST(OrbDescriptor, IntensityCentroidPointsToTheBrightSide) {
  // Bright right half: angle 0; bright bottom half (y down): 90.
  cv::Mat image(64, 64, CV_8UC1, cv::Scalar(0));
  image(cv::Rect(32, 0, 32, 64)).setTo(200);
  EXPECT_NEAR(IntensityCentroidAngle(image, 32, 32), 0.0f, 1.0f);
  image.setTo(0);
  image(cv::Rect(0, 33, 64, 31)).setTo(200);
  EXPECT_NEAR(IntensityCentroidAngle(image, 32, 32), 90.0f, 1.0f);
  image.setTo(0);
  image(cv::Rect(0, 0, 32, 32)).setTo(200);  // top-left quadrant: 225
  EXPECT_NEAR(IntensityCentroidAngle(image, 32, 32), 225.0f, 2.0f);
}

TEST(OrbDescriptor, SteeringByTheRotationUndoesIt) {
  // The descriptor of a patch at angle a equals that of the patch rotated by 90 degrees, steered by a - 90.
  const cv::Mat image = MakeSyntheticTrainingImage(4, cv::Size(200, 200));
  cv::Mat smoothed, rotated, rotated_smoothed;
  SmoothForDescriptor(image, smoothed);
  cv::rotate(smoothed, rotated_smoothed, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int x = 80, y = 120;
  // (x, y) -> (y, W - 1 - x) in the rotated image.
  const Descriptor d1 = ComputeSteeredBrief(smoothed, x, y, 30.0f);
  const Descriptor d2 = ComputeSteeredBrief(rotated_smoothed, y, image.cols - 1 - x, 30.0f - 90.0f + 360.0f);
  EXPECT_LE(HammingDistance(d1, d2), 4);  // rounding of the steered points may differ at ties
  EXPECT_GT(HammingDistance(d1, ComputeSteeredBrief(rotated_smoothed, y, image.cols - 1 - x, 30.0f)), 40);
}

}  // namespace
}  // namespace semslam
