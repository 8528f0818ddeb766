// `semslam segment` end to end: JSON on stdout, colourized PNGs, scores against ground truth, errors.

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "support/test_support.h"

namespace semslam {
namespace {

using testing::CommandResult;
using testing::RunSemslam;

class SegmentCommand : public ::testing::Test {
 protected:
  void SetUp() override { SEMSLAM_REQUIRE_BINARY(); }
};

TEST_F(SegmentCommand, ScoresTruthNoisyAgainstTheTruth) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir / "image_0");
  std::filesystem::create_directories(dir / "label_0");
  cv::Mat truth(120, 400, CV_8UC1, cv::Scalar(10));
  truth.rowRange(60, 120).setTo(0);
  truth(cv::Rect(100, 20, 120, 80)).setTo(2);
  for (int f = 0; f < 3; ++f) {
    ASSERT_TRUE(cv::imwrite((dir / "image_0" / cv::format("%06d.png", f)).string(),
                            cv::Mat(120, 400, CV_8UC1, cv::Scalar(90))));
    ASSERT_TRUE(cv::imwrite((dir / "label_0" / cv::format("%06d.png", f)).string(), truth));
  }
  const CommandResult r =
      RunSemslam({"segment", "--segmenter", "truth-noisy:0.2", "--images", (dir / "image_0").string(),
                  "--truth", (dir / "label_0").string(), "--out", (dir / "out").string()});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.Describe();
  const auto json = nlohmann::json::parse(r.out);
  EXPECT_EQ(json["images"], 3);
  EXPECT_NEAR(json["pixel_accuracy"].get<double>(), 0.8, 0.02);
  EXPECT_GT(json["class_histogram"]["road"].get<double>(), 0.3);
  EXPECT_TRUE(json.contains("mean_iou"));
  EXPECT_EQ(json["per_image"].size(), 3u);
  const cv::Mat colored = cv::imread((dir / "out" / "000001_labels.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(colored.empty());
  EXPECT_EQ(colored.type(), CV_8UC3);
  EXPECT_EQ(colored.size(), truth.size());
  const cv::Mat ids = cv::imread((dir / "out" / "000001_trainids.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(ids.type(), CV_8UC1);
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "segment.json"));

  // The sequence's label_0 next to image_0 is found without --truth.
  const CommandResult sibling =
      RunSemslam({"segment", "--segmenter", "truth-noisy:0", "--images", (dir / "image_0").string()});
  ASSERT_EQ(sibling.exit_code, 0);
  EXPECT_NEAR(nlohmann::json::parse(sibling.out)["class_histogram"]["sky"].get<double>(), 0.4, 1e-9);

  // A truth of another shape (another image's) is refused, and the images done before it are not kept.
  std::filesystem::copy(dir / "label_0", dir / "other");
  ASSERT_TRUE(
      cv::imwrite((dir / "other" / "000002.png").string(), cv::Mat(100, 100, CV_8UC1, cv::Scalar(0))));
  const CommandResult shape =
      RunSemslam({"segment", "--segmenter", "truth-noisy:0", "--images", (dir / "image_0").string(),
                  "--truth", (dir / "other").string(), "--out", (dir / "out2").string()});
  EXPECT_NE(shape.exit_code, 0);
  EXPECT_NE(shape.err.find("000002.png"), std::string::npos) << shape.err;
  EXPECT_NE(shape.err.find("another shape"), std::string::npos) << shape.err;
  EXPECT_FALSE(std::filesystem::exists(dir / "out2" / "000000_labels.png"));
}

TEST_F(SegmentCommand, OnnxCardAndErrors) {
  testing::TempDir dir;
  ASSERT_TRUE(cv::imwrite((dir / "red.png").string(), cv::Mat(8, 16, CV_8UC3, cv::Scalar(0, 0, 255))));
  const std::string red = (dir / "red.png").string();
  const CommandResult r = RunSemslam(
      {"segment", "--segmenter", "onnx:" SEMSLAM_SEMANTICS_TEST_DATA "/tiny_segnet.yaml", "--images", red});
  ASSERT_EQ(r.exit_code, 0) << r.out << r.Describe();
  EXPECT_NEAR(nlohmann::json::parse(r.out)["class_histogram"]["road"].get<double>(), 1.0, 1e-9);
  EXPECT_NE(RunSemslam({"segment", "--segmenter", "bogus:1", "--images", red}).exit_code, 0);
  EXPECT_NE(RunSemslam({"segment", "--segmenter", "labels:/nonexistent", "--images", red}).exit_code, 0);
  EXPECT_NE(RunSemslam({"segment", "--segmenter", "none", "--images", red}).exit_code, 0);
  const std::string missing = (dir / "missing.png").string();
  EXPECT_NE(RunSemslam({"segment", "--segmenter", "truth-noisy:0.1", "--images", missing}).exit_code, 0);
}

}  // namespace
}  // namespace semslam
