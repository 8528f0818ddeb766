// Segmentation storage and sampling, scores -> distributions, the class table.

#include "semslam/semantics/segmentation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/core.hpp>
#include <span>
#include <vector>

#include "semslam/core/error.h"
#include "semslam/semantics/class_table.h"

namespace semslam {
namespace {

TEST(ClassTable, NamesColorsDynamicAndLabelIds) {
  ASSERT_EQ(ClassTable().size(), 19u);
  EXPECT_EQ(ClassName(0), "road");
  EXPECT_EQ(ClassName(6), "traffic light");
  EXPECT_EQ(ClassName(18), "bicycle");
  EXPECT_EQ(ClassName(kNoLabel), "none");
  EXPECT_EQ(ClassKey(7), "traffic_sign");
  EXPECT_EQ(ClassColor(0), (Rgb{128, 64, 128}));
  EXPECT_EQ(ClassColor(13), (Rgb{0, 0, 142}));
  EXPECT_EQ(ClassColor(10), (Rgb{70, 130, 180}));
  EXPECT_EQ(ClassColor(kNoLabel), (Rgb{0, 0, 0}));
  int dynamic = 0;
  for (int c = 0; c < kNumClasses; ++c) dynamic += IsDynamicClass(c) ? 1 : 0;
  EXPECT_EQ(dynamic, 8);
  EXPECT_TRUE(IsDynamicClass(TrainId(SemanticClass::kPerson)));
  EXPECT_TRUE(IsDynamicClass(TrainId(SemanticClass::kBicycle)));
  EXPECT_FALSE(IsDynamicClass(TrainId(SemanticClass::kBuilding)));
  EXPECT_FALSE(IsDynamicClass(kNoLabel));
  EXPECT_EQ(TrainIdFromName("TrafficLight"), 6);
  EXPECT_EQ(TrainIdFromName("traffic_sign"), 7);
  EXPECT_EQ(TrainIdFromName("Sky"), 10);
  EXPECT_EQ(TrainIdFromName("caravan"), std::nullopt);
  // Cityscapes labelIds: road 7, sidewalk 8, building 11, pole 17, sky 23, car 26, bicycle 33; parking 9 and
  // ego vehicle 1 are not evaluated.
  EXPECT_EQ(LabelIdToTrainId(7), 0);
  EXPECT_EQ(LabelIdToTrainId(8), 1);
  EXPECT_EQ(LabelIdToTrainId(11), 2);
  EXPECT_EQ(LabelIdToTrainId(17), 5);
  EXPECT_EQ(LabelIdToTrainId(23), 10);
  EXPECT_EQ(LabelIdToTrainId(26), 13);
  EXPECT_EQ(LabelIdToTrainId(31), 16);
  EXPECT_EQ(LabelIdToTrainId(33), 18);
  EXPECT_EQ(LabelIdToTrainId(9), kNoLabel);
  EXPECT_EQ(LabelIdToTrainId(1), kNoLabel);
  EXPECT_EQ(LabelIdToTrainId(-1), kNoLabel);
  EXPECT_EQ(LabelIdToTrainIdTable()[255], kNoLabel);
}

TEST(Segmentation, LabelsMapBackToInputPixels) {
  // 4x2 labels over an 8x4 image: each stored cell covers 2x2 input pixels.
  cv::Mat labels = (cv::Mat_<std::uint8_t>(2, 4) << 0, 1, 2, 3, 8, 10, 13, 255);
  const Segmentation s = Segmentation::FromLabels(labels, cv::Size(8, 4), 0.75f);
  EXPECT_EQ(s.storage(), Segmentation::Storage::kLabels);
  EXPECT_EQ(s.input_size(), cv::Size(8, 4));
  EXPECT_EQ(s.storage_size(), cv::Size(4, 2));
  EXPECT_EQ(s.LabelAt(0, 0), 0);
  EXPECT_EQ(s.LabelAt(1.4f, 1.4f), 0);
  EXPECT_EQ(s.LabelAt(1.6f, 1.4f), 1);  // sub-pixel: x = 1.6 lies in input pixel 2, stored column 1
  EXPECT_EQ(s.LabelAt(7.0f, 0.0f), 3);
  EXPECT_EQ(s.LabelAt(5.0f, 3.0f), 13);
  EXPECT_EQ(s.LabelAt(7.0f, 3.0f), kNoLabel);
  EXPECT_EQ(s.LabelAt(-0.6f, 0.0f), kNoLabel);
  EXPECT_EQ(s.LabelAt(7.6f, 0.0f), kNoLabel);
  EXPECT_EQ(s.LabelAt(NAN, 0.0f), kNoLabel);
  ClassLogProbs p;
  ASSERT_TRUE(s.Sample(Eigen::Vector2d(3.0, 3.0), &p));
  EXPECT_NEAR(std::exp(p[10]), 0.75, 1e-6);
  EXPECT_NEAR(std::exp(p[0]), 0.25 / 18, 1e-7);
  p.fill(1.0f);
  EXPECT_FALSE(s.Sample(Eigen::Vector2d(7.0, 3.0), &p));
  EXPECT_EQ(p[0], 1.0f);  // untouched
  EXPECT_FALSE(s.Sample(Eigen::Vector2d(100.0, 3.0), &p));
  const cv::Mat full = s.LabelsAtInputSize();
  ASSERT_EQ(full.size(), cv::Size(8, 4));
  EXPECT_EQ(full.at<std::uint8_t>(3, 5), 13);
  EXPECT_EQ(full.at<std::uint8_t>(0, 2), 1);
  EXPECT_NEAR(s.Confidence().at<float>(0, 0), 0.75f, 1e-6);
  EXPECT_EQ(s.Confidence().at<float>(1, 3), 0.0f);
}

TEST(Segmentation, PerPixelConfidenceReplacesAlpha) {
  cv::Mat labels = (cv::Mat_<std::uint8_t>(1, 2) << 2, 5);
  cv::Mat confidence = (cv::Mat_<std::uint8_t>(1, 2) << 255, 51);  // 1.0 and 0.2
  const Segmentation s = Segmentation::FromLabels(labels, cv::Size(2, 1), 0.5f, confidence);
  ClassLogProbs p;
  ASSERT_TRUE(s.Sample(Eigen::Vector2d(1, 0), &p));
  EXPECT_NEAR(std::exp(p[5]), 0.2, 1e-6);
  EXPECT_NEAR(std::exp(p[0]), 0.8 / 18, 1e-6);
  ASSERT_TRUE(s.Sample(Eigen::Vector2d(0, 0), &p));
  EXPECT_NEAR(p[2], 0.0, 1e-6);
  EXPECT_NEAR(p[0], kMinObservationLogProbability, 1e-6);
  EXPECT_THROW(Segmentation::FromLabels(labels, cv::Size(2, 1), 0.01f), InvalidArgument);
  EXPECT_THROW(Segmentation::FromLabels(cv::Mat(1, 2, CV_16UC1), cv::Size(2, 1), 0.5f), InvalidArgument);
}

// Logits (unlabeled 0, road 1, car 2): softmax = (0.0900306, 0.2447285, 0.6652410); the unlabeled share is
// spread over the 19 classes (0.0900306 / 19 = 0.0047385 each): road 0.2494669, car 0.6699794, every other
// class 0.0047385.
TEST(Segmentation, ScoresBecomeClassDistributions) {
  std::vector<cv::Mat> planes = {cv::Mat(2, 3, CV_32FC1, cv::Scalar(0.0f)),
                                 cv::Mat(2, 3, CV_32FC1, cv::Scalar(1.0f)),
                                 cv::Mat(2, 3, CV_32FC1, cv::Scalar(2.0f))};
  const std::vector<std::uint8_t> mapping = {kNoLabel, 0, 13};
  const Segmentation s = SegmentationFromScores(planes, ScoreKind::kLogits, mapping, cv::Size(6, 4));
  EXPECT_EQ(s.storage(), Segmentation::Storage::kLogProbabilities);
  EXPECT_EQ(s.storage_size(), cv::Size(3, 2));
  ClassLogProbs p;
  ASSERT_TRUE(s.Sample(Eigen::Vector2d(5, 3), &p));
  EXPECT_NEAR(std::exp(p[0]), 0.2494669, 1e-6);
  EXPECT_NEAR(std::exp(p[13]), 0.6699794, 1e-6);
  EXPECT_NEAR(std::exp(p[4]), 0.0047385, 1e-6);
  double sum = 0.0;
  for (float v : p) sum += std::exp(v);
  EXPECT_NEAR(sum, 1.0, 1e-5);
  EXPECT_EQ(s.LabelAt(0, 0), 13);
  EXPECT_NEAR(s.Confidence().at<float>(1, 2), 0.6699794, 1e-5);

  // Probabilities that do not sum to 1 are renormalized; two channels of one class add up.
  std::vector<cv::Mat> probs = {cv::Mat(1, 1, CV_32FC1, cv::Scalar(0.2f)),
                                cv::Mat(1, 1, CV_32FC1, cv::Scalar(0.2f)),
                                cv::Mat(1, 1, CV_32FC1, cv::Scalar(0.4f))};
  const std::vector<std::uint8_t> two_roads = {0, 0, 10};
  const Segmentation q = SegmentationFromScores(probs, ScoreKind::kProbabilities, two_roads, cv::Size(1, 1));
  ASSERT_TRUE(q.Sample(Eigen::Vector2d(0, 0), &p));
  EXPECT_NEAR(std::exp(p[0]), 0.5, 1e-6);
  EXPECT_NEAR(std::exp(p[10]), 0.5, 1e-6);
  EXPECT_NEAR(std::exp(p[1]), kMinObservationProbability, 1e-8);  // floored

  EXPECT_THROW(
      SegmentationFromScores(planes, ScoreKind::kLogits, std::span(two_roads).subspan(0, 2), cv::Size(1, 1)),
      InvalidArgument);
}

TEST(Segmentation, CompactedKeepsLabelsAndConfidence) {
  std::vector<cv::Mat> planes(kNumClasses);
  for (int c = 0; c < kNumClasses; ++c)
    planes[static_cast<size_t>(c)] = cv::Mat(4, 4, CV_32FC1, cv::Scalar(0.0f));
  planes[3].setTo(3.0f);
  planes[7].colRange(2, 4).setTo(5.0f);
  std::vector<std::uint8_t> mapping(kNumClasses);
  for (int c = 0; c < kNumClasses; ++c) mapping[static_cast<size_t>(c)] = static_cast<std::uint8_t>(c);
  const Segmentation s = SegmentationFromScores(planes, ScoreKind::kLogits, mapping, cv::Size(8, 8));
  const Segmentation compact = s.Compacted();
  EXPECT_EQ(compact.storage(), Segmentation::Storage::kLabels);
  EXPECT_LT(compact.MemoryBytes() * 30, s.MemoryBytes());
  EXPECT_EQ(cv::countNonZero(compact.Labels() != s.Labels()), 0);
  ClassLogProbs a, b;
  ASSERT_TRUE(s.Sample(Eigen::Vector2d(1, 1), &a));
  ASSERT_TRUE(compact.Sample(Eigen::Vector2d(1, 1), &b));
  EXPECT_NEAR(std::exp(a[3]), std::exp(b[3]), 0.01);
}

}  // namespace
}  // namespace semslam
