// Semantic point cloud PLY, per-class counts, map-point label accuracy, segmentation scores, colourized
// labels.

#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/core.hpp>

#include "semslam/core/error.h"
#include "semslam/semantics/semantic_outputs.h"
#include "support/test_support.h"

namespace semslam {
namespace {

std::vector<SemanticPoint> SomePoints() {
  return {
      {Eigen::Vector3d(1.5, -2.25, 10.125), 0, 0.95f, 7},
      {Eigen::Vector3d(-3.0, 0.5, 22.0), 13, 0.5f, 2},
      {Eigen::Vector3d(0.0, 0.0, 1e3), kNoLabel, 0.0f, 0},
      {Eigen::Vector3d(4.0, 1.0, 5.0), 10, 0.25f, 1},
  };
}

TEST(SemanticPly, BinaryAndAsciiRoundTrip) {
  testing::TempDir dir;
  const auto points = SomePoints();
  for (PlyFormat format : {PlyFormat::kBinary, PlyFormat::kAscii}) {
    const auto path = dir / (format == PlyFormat::kBinary ? "map.ply" : "map_ascii.ply");
    WriteSemanticPly(path, points, format);
    const auto read = ReadSemanticPly(path);
    ASSERT_EQ(read.size(), points.size());
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_TRUE(read[i].position.isApprox(points[i].position, 1e-6)) << i;
      EXPECT_EQ(read[i].label, points[i].label);
      EXPECT_FLOAT_EQ(read[i].confidence, points[i].confidence);
      EXPECT_EQ(read[i].observations, points[i].observations);
    }
  }
  // No temporary files are left behind, and the header names the properties.
  EXPECT_EQ(
      std::distance(std::filesystem::directory_iterator(dir.path()), std::filesystem::directory_iterator()),
      2);
  std::ifstream in(dir / "map_ascii.ply");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("property uchar red"), std::string::npos);
  EXPECT_NE(text.find("property uchar label"), std::string::npos);
  EXPECT_NE(text.find("property float confidence"), std::string::npos);
  EXPECT_NE(text.find("property int observations"), std::string::npos);
  EXPECT_NE(text.find("\n1.5 -2.25 10.125 128 64 128 0 0.95 7\n"),
            std::string::npos);  // road: palette colour

  std::vector<SemanticPoint> bad = points;
  bad[1].position.x() = NAN;
  EXPECT_THROW(WriteSemanticPly(dir / "bad.ply", bad), InvalidArgument);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.ply"));
}

TEST(SemanticPly, ReaderRejectsBrokenFiles) {
  testing::TempDir dir;
  std::ofstream(dir / "a.ply") << "not a ply\n";
  EXPECT_THROW(ReadSemanticPly(dir / "a.ply"), InputError);
  std::ofstream(dir / "b.ply")
      << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
         "property float z\nend_header\n1 2 3\n4 5\n";
  try {
    ReadSemanticPly(dir / "b.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().line, 9);
  }
  WriteSemanticPly(dir / "c.ply", SomePoints());
  std::filesystem::resize_file(dir / "c.ply", std::filesystem::file_size(dir / "c.ply") - 5);
  EXPECT_THROW(ReadSemanticPly(dir / "c.ply"), InputError);
  EXPECT_THROW(ReadSemanticPly(dir / "missing.ply"), InputError);
}

TEST(SemanticOutputs, PointFromDistribution) {
  LabelDistribution d;
  EXPECT_EQ(ToSemanticPoint(Eigen::Vector3d(1, 2, 3), d).label, kNoLabel);
  EXPECT_EQ(ToSemanticPoint(Eigen::Vector3d(1, 2, 3), d).confidence, 0.0f);
  d.FuseLabel(8, 0.7f);
  d.FuseLabel(8, 0.7f);
  const SemanticPoint p = ToSemanticPoint(Eigen::Vector3d(1, 2, 3), d);
  EXPECT_EQ(p.position, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(p.label, 8);
  EXPECT_EQ(p.observations, 2);
  EXPECT_FLOAT_EQ(p.confidence, d.Confidence());
}

TEST(SemanticOutputs, CountsAndPointAccuracy) {
  const auto points = SomePoints();
  const ClassCounts counts = CountLabels(points);
  EXPECT_EQ(counts[0], 1u);
  EXPECT_EQ(counts[13], 1u);
  EXPECT_EQ(counts[10], 1u);
  EXPECT_EQ(counts[kNumClasses], 1u);
  // Truth: road below z = 15 (points 0 and 3), car beyond, nothing far away.
  const GroundTruthClassFn truth = [](const Eigen::Vector3d& p) -> std::optional<int> {
    if (p.z() > 100) return std::nullopt;
    return p.z() < 15 ? 0 : 13;
  };
  auto far_unlabeled = points;
  far_unlabeled.push_back({Eigen::Vector3d(0, 0, 3), kNoLabel, 0.0f, 0});
  const LabelAccuracy a = EvaluatePointLabels(far_unlabeled, truth);
  EXPECT_EQ(a.evaluated, 3u);
  EXPECT_EQ(a.correct, 2u);
  EXPECT_EQ(a.unlabeled, 1u);
  EXPECT_EQ(a.no_truth, 1u);
  EXPECT_NEAR(a.Accuracy(), 2.0 / 3.0, 1e-12);
  EXPECT_NEAR(*a.ClassAccuracy(0), 0.5, 1e-12);
  EXPECT_NEAR(*a.ClassAccuracy(13), 1.0, 1e-12);
  EXPECT_FALSE(a.ClassAccuracy(5).has_value());
}

// truth (road road sidewalk sidewalk none), prediction (road sidewalk sidewalk sidewalk road):
// 4 scored pixels, 3 right; IoU road = 1 / (1 + 1) = 0.5, sidewalk = 2 / 3; mIoU = 0.583333.
TEST(SemanticOutputs, SegmentationScoreByHand) {
  const cv::Mat truth = (cv::Mat_<std::uint8_t>(1, 5) << 0, 0, 1, 1, 255);
  const cv::Mat predicted = (cv::Mat_<std::uint8_t>(1, 5) << 0, 1, 1, 1, 0);
  SegmentationScore score;
  score.Add(predicted, truth);
  EXPECT_EQ(score.pixels(), 4u);
  EXPECT_NEAR(score.PixelAccuracy(), 0.75, 1e-12);
  EXPECT_NEAR(*score.ClassIou(0), 0.5, 1e-12);
  EXPECT_NEAR(*score.ClassIou(1), 2.0 / 3.0, 1e-12);
  EXPECT_FALSE(score.ClassIou(2).has_value());
  EXPECT_NEAR(score.MeanIou(), 0.5833333333, 1e-9);
  EXPECT_NEAR(score.MeanIouOverTruthClasses(), 0.5833333333, 1e-9);
  EXPECT_EQ(score.Count(0, 1), 1u);
  // A missing prediction is wrong.
  score.Add((cv::Mat_<std::uint8_t>(1, 1) << 255), (cv::Mat_<std::uint8_t>(1, 1) << 1));
  EXPECT_NEAR(score.PixelAccuracy(), 0.6, 1e-12);
  EXPECT_EQ(score.Count(1, kNumClasses), 1u);
  // A class predicted where the truth has another counts in MeanIou (IoU 0), not over the truth's classes.
  score.Add((cv::Mat_<std::uint8_t>(1, 1) << 13), (cv::Mat_<std::uint8_t>(1, 1) << 0));
  EXPECT_NEAR(*score.ClassIou(13), 0.0, 1e-12);
  EXPECT_NEAR(score.MeanIou(), (1.0 / 3.0 + 2.0 / 4.0 + 0.0) / 3.0, 1e-9);
  EXPECT_NEAR(score.MeanIouOverTruthClasses(), (1.0 / 3.0 + 2.0 / 4.0) / 2.0, 1e-9);
  EXPECT_THROW(score.Add(predicted, truth.colRange(0, 4)), InvalidArgument);
}

TEST(SemanticOutputs, ColorizedLabels) {
  const cv::Mat ids = (cv::Mat_<std::uint8_t>(1, 3) << 13, 0, 255);
  const cv::Mat colored = ColorizeLabels(ids);
  ASSERT_EQ(colored.type(), CV_8UC3);
  EXPECT_EQ(colored.at<cv::Vec3b>(0, 0), cv::Vec3b(142, 0, 0));  // car (0, 0, 142) as BGR
  EXPECT_EQ(colored.at<cv::Vec3b>(0, 1), cv::Vec3b(128, 64, 128));
  EXPECT_EQ(colored.at<cv::Vec3b>(0, 2), cv::Vec3b(0, 0, 0));
  const cv::Mat blended = ColorizeLabels(ids, cv::Mat(1, 3, CV_8UC1, cv::Scalar(100)), 0.5);
  EXPECT_EQ(blended.at<cv::Vec3b>(0, 0), cv::Vec3b(121, 50, 50));
}

}  // namespace
}  // namespace semslam
