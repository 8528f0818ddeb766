#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "semslam/core/error.h"
#include "semslam/io/sequence.h"
#include "support/test_support.h"
#include "test_files.h"

namespace semslam {
namespace {

cv::Mat Gradient(int width, int height, int type) {
  cv::Mat image(height, width, type);
  image.forEach<uchar>([](uchar&, const int*) {});
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (type == CV_8UC1) image.at<uchar>(y, x) = static_cast<uchar>((x * 7 + y * 3) % 256);
      if (type == CV_16UC1) image.at<uint16_t>(y, x) = static_cast<uint16_t>(x * 1000 + y);
      if (type == CV_8UC3) image.at<cv::Vec3b>(y, x) = cv::Vec3b(x % 256, y % 256, (x + y) % 256);
    }
  }
  return image;
}

TEST(WritePng, RoundTripsGreyAnd16Bit) {
  testing::TempDir dir;
  const cv::Mat grey = Gradient(37, 23, CV_8UC1);
  WritePng(dir / "sub/grey.png", grey);  // creates the folder
  const cv::Mat read = cv::imread((dir / "sub/grey.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(read.type(), CV_8UC1);
  EXPECT_EQ(cv::norm(read, grey, cv::NORM_INF), 0.0);

  const cv::Mat depth = Gradient(31, 17, CV_16UC1);
  WritePng(dir / "depth.png", depth, 9);
  const cv::Mat depth_read = cv::imread((dir / "depth.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(depth_read.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(depth_read, depth, cv::NORM_INF), 0.0);

  // No temporary files are left beside the outputs.
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 2);  // sub/ and depth.png
  EXPECT_THROW(WritePng(dir / "empty.png", cv::Mat()), InvalidArgument);
}

TEST(ReadGreyImage, ConvertsColourAndReportsBadFiles) {
  testing::TempDir dir;
  const cv::Mat colour = Gradient(20, 10, CV_8UC3);
  WritePng(dir / "colour.png", colour);
  const cv::Mat grey = ReadGreyImage(dir / "colour.png");
  EXPECT_EQ(grey.type(), CV_8UC1);
  EXPECT_EQ(grey.cols, 20);
  EXPECT_EQ(grey.rows, 10);
  // Pixel (5, 3): B=5, G=3, R=8 -> 0.299 R + 0.587 G + 0.114 B = 4.73.
  EXPECT_NEAR(grey.at<uchar>(3, 5), 5, 1);

  EXPECT_INPUT_ERROR(ReadGreyImage(dir / "none.png"), "none.png", "not found");
  testing::WriteText(dir / "broken.png", "this is not a PNG");
  EXPECT_INPUT_ERROR(ReadGreyImage(dir / "broken.png"), "broken.png", "cannot decode");
}

}  // namespace
}  // namespace semslam
