// Place recognition end to end: features -> vocabulary -> database -> the right image comes first.

#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "semslam/features/orb_extractor.h"
#include "semslam/features/orb_pattern.h"
#include "semslam/place/bow_matching.h"
#include "semslam/place/keyframe_database.h"
#include "semslam/place/retrieval_evaluation.h"
#include "semslam/place/vocabulary.h"
#include "support/test_support.h"

namespace semslam {
namespace {

// A vocabulary trained on procedural images only (no test image among them).
const Vocabulary& SyntheticVocabulary() {
  static const Vocabulary vocabulary = [] {
    OrbOptions orb;
    orb.num_features = 1000;
    const OrbExtractor extractor(orb);
    std::vector<std::vector<Descriptor>> images;
    for (int i = 0; i < 60; ++i)
      images.push_back(extractor.Extract(MakeSyntheticTrainingImage(1000 + i)).descriptors);
    VocabularyTrainingOptions options;
    options.branching = 10;
    options.depth = 4;
    return Vocabulary::Train(images, options);
  }();
  return vocabulary;
}

cv::Mat Perturb(const cv::Mat& image, int seed) {
  // A few pixels of motion, a small rotation, brightness change and noise.
  const cv::Mat m =
      cv::getRotationMatrix2D(cv::Point2f(image.cols / 2.0f, image.rows / 2.0f), 2.0 + seed % 3, 1.0);
  cv::Mat moved;
  cv::Mat shift = m.clone();
  shift.at<double>(0, 2) += 6;
  shift.at<double>(1, 2) -= 4;
  cv::warpAffine(image, moved, shift, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  cv::Mat noise(image.size(), CV_8UC1);
  cv::randu(noise, 0, 12);
  moved = moved * 0.9 + noise;
  return moved;
}

TEST(Retrieval, PerturbedImagesFindTheirOriginalFirst) {
  const Vocabulary& vocabulary = SyntheticVocabulary();
  const OrbExtractor extractor;
  KeyFrameDatabase db(vocabulary.size());
  std::vector<cv::Mat> images;
  for (int i = 0; i < 30; ++i) {
    images.push_back(MakeSyntheticTrainingImage(5000 + i));
    db.Add(static_cast<std::uint64_t>(i), vocabulary.Transform(extractor.Extract(images.back()).descriptors));
  }
  for (int i = 0; i < 30; ++i) {
    const BowVector query =
        vocabulary.Transform(extractor.Extract(Perturb(images[static_cast<size_t>(i)], i)).descriptors);
    const auto results = db.Query(query);
    ASSERT_GE(results.size(), 2u);
    EXPECT_EQ(results[0].id, static_cast<std::uint64_t>(i));
    // A small vocabulary and images from one generator: unrelated images share many words (score ~0.25).
    EXPECT_GT(results[0].score, 1.15 * results[1].score) << "image " << i;
    // The same image itself scores 1.
    EXPECT_NEAR(
        db.Query(vocabulary.Transform(extractor.Extract(images[static_cast<size_t>(i)]).descriptors))[0]
            .score,
        1.0, 1e-12);
  }
}

TEST(Retrieval, KittiFramesFindTheirNeighboursWithAVocabularyNeverTrainedOnKitti) {
  SEMSLAM_REQUIRE_SHARED_DATA(root, "kitti_odom_07_3dv");
  const Vocabulary& vocabulary = SyntheticVocabulary();
  const OrbExtractor extractor;
  auto frame = [&](int i) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06d.png", i);
    return cv::imread((root / "sequences" / "07" / "image_0" / name).string(), cv::IMREAD_GRAYSCALE);
  };
  KeyFrameDatabase db(vocabulary.size());
  for (int i = 0; i < 160; i += 10)
    db.Add(static_cast<std::uint64_t>(i), vocabulary.Transform(extractor.Extract(frame(i)).descriptors));
  // Each query lies 3 frames (about 2-3 m) after a database frame and 7 frames (up to 6 m) before the next.
  int nearest = 0, bracketing = 0, total = 0;
  for (int i = 3; i < 160; i += 10) {
    const auto results = db.Query(vocabulary.Transform(extractor.Extract(frame(i)).descriptors));
    ++total;
    if (results.empty()) continue;
    nearest += results[0].id == static_cast<std::uint64_t>(i - 3);
    bracketing += results[0].id == static_cast<std::uint64_t>(i - 3) ||
                  results[0].id == static_cast<std::uint64_t>(i + 7);
  }
  EXPECT_EQ(bracketing, total) << bracketing << " of " << total;
  EXPECT_GE(nearest, total - 3) << nearest << " of " << total;
}

TEST(Retrieval, EvaluationCountsRevisitsAndRightAnswers) {
  // 30 places along a straight street, then the first 10 again (perturbed views, same poses).
  const Vocabulary& vocabulary = SyntheticVocabulary();
  const OrbExtractor extractor;
  std::vector<std::vector<Descriptor>> descriptors;
  std::vector<Eigen::Vector3d> positions, directions;
  std::vector<cv::Mat> places;
  for (int i = 0; i < 30; ++i) {
    places.push_back(MakeSyntheticTrainingImage(7000 + i));
    descriptors.push_back(extractor.Extract(places.back()).descriptors);
    positions.emplace_back(0, 0, 10.0 * i);
    directions.emplace_back(0, 0, 1);
  }
  for (int i = 0; i < 10; ++i) {
    descriptors.push_back(extractor.Extract(Perturb(places[static_cast<size_t>(i)], i)).descriptors);
    positions.emplace_back(0.5, 0, 10.0 * i);
    directions.emplace_back(0, 0, 1);
  }
  RetrievalOptions options;
  options.database_every = 1;
  options.exclude_recent = 15;
  const RetrievalResult r = EvaluateRetrieval(vocabulary, descriptors, positions, directions, options);
  EXPECT_EQ(r.queries, 40 - 15);
  EXPECT_EQ(r.revisits, 10);
  EXPECT_EQ(r.top1, 10);
  EXPECT_EQ(r.top5, 10);
  EXPECT_GT(r.median_true_score, r.median_other_score);
  EXPECT_DOUBLE_EQ(r.Top1Rate(), 1.0);
  // Looking the other way is not the same place.
  for (int i = 30; i < 40; ++i) directions[static_cast<size_t>(i)] = {0, 0, -1};
  EXPECT_EQ(EvaluateRetrieval(vocabulary, descriptors, positions, directions, options).revisits, 0);
}

TEST(BowMatching, MatchesAShiftedImageThroughTheDirectIndex) {
  const Vocabulary& vocabulary = SyntheticVocabulary();
  const OrbExtractor extractor;
  const cv::Mat image = MakeSyntheticTrainingImage(77, cv::Size(1241, 376));
  cv::Mat shifted;
  cv::warpAffine(image, shifted, cv::Matx23d(1, 0, 9, 0, 1, 2), image.size(), cv::INTER_NEAREST,
                 cv::BORDER_REFLECT_101);
  const FeatureSet f1 = extractor.Extract(image), f2 = extractor.Extract(shifted);
  BowVector b1, b2;
  FeatureVector v1, v2;
  vocabulary.Transform(f1.descriptors, &b1, &v1);
  vocabulary.Transform(f2.descriptors, &b2, &v2);
  const auto matches = MatchByBow(f1, v1, f2, v2);
  int n = 0, right = 0;
  std::vector<int> used(f2.size(), 0);
  for (size_t i = 0; i < f1.size(); ++i) {
    if (matches[i] < 0) continue;
    ++n;
    ++used[static_cast<size_t>(matches[i])];
    const Eigen::Vector2f d = f2.keypoints[static_cast<size_t>(matches[i])].pixel - f1.keypoints[i].pixel;
    right += (d - Eigen::Vector2f(9, 2)).norm() <
             1.5f * f1.pyramid.scale[static_cast<size_t>(f1.keypoints[i].level)];
  }
  EXPECT_GT(n, 600);
  EXPECT_GT(right, 0.95 * n);  // the rest: windows of a repeated grid
  for (const int u : used) EXPECT_LE(u, 1);
  // Unrelated images share few matches.
  const FeatureSet f3 = extractor.Extract(MakeSyntheticTrainingImage(78, cv::Size(1241, 376)));
  BowVector b3;
  FeatureVector v3;
  vocabulary.Transform(f3.descriptors, &b3, &v3);
  const auto wrong = MatchByBow(f1, v1, f3, v3);
  EXPECT_LT(std::count_if(wrong.begin(), wrong.end(), [](int m) { return m >= 0; }), n / 10);
}

}  // namespace
}  // namespace semslam

namespace semslam {
namespace {

TEST(DefaultVocabulary, IsInTheTreeLoadsAndRecognizesPlaces) {
  ::unsetenv("SEMSLAM_VOCABULARY");
  const auto path = DefaultVocabularyPath();
  ASSERT_TRUE(std::filesystem::exists(path)) << path << " (made by scripts/make-vocabulary.sh)";
  const Vocabulary vocabulary = Vocabulary::Load(path);
  EXPECT_EQ(vocabulary.descriptor_pattern(), OrbDescriptorPattern::kSemslam);
  EXPECT_GT(vocabulary.size(), 5000u);
  EXPECT_LT(std::filesystem::file_size(path), 1600000u);
  const OrbExtractor extractor;
  KeyFrameDatabase db(vocabulary.size());
  std::vector<cv::Mat> images;
  for (int i = 0; i < 20; ++i) {
    images.push_back(MakeSyntheticTrainingImage(9000 + i, cv::Size(1241, 376)));
    db.Add(static_cast<std::uint64_t>(i), vocabulary.Transform(extractor.Extract(images.back()).descriptors));
  }
  for (int i = 0; i < 20; ++i) {
    const auto results = db.Query(
        vocabulary.Transform(extractor.Extract(Perturb(images[static_cast<size_t>(i)], i)).descriptors));
    ASSERT_FALSE(results.empty());
    EXPECT_EQ(results[0].id, static_cast<std::uint64_t>(i));
  }
}

}  // namespace
}  // namespace semslam
