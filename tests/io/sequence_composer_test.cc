#include "semslam/io/sequence_composer.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <csignal>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/io/image_folder.h"
#include "semslam/io/sequence.h"
#include "support/test_support.h"

namespace semslam {
namespace {

TEST(ParseFrameList, RangesRunBothWaysAndSingleFramesStayPut) {
  EXPECT_EQ(ParseFrameList("0-3", 10), (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(ParseFrameList("3-1,7,0-0", 10), (std::vector<size_t>{3, 2, 1, 7, 0}));
  for (const char* bad : {"", "1,", ",1", "1-", "a-3", "1-2-3", "-1", "1;2"}) {
    EXPECT_THROW(ParseFrameList(bad, 10), InvalidArgument) << bad;
  }
  // Frames the source does not have, refused before a range is expanded (a billion frames would not fit).
  for (const char* beyond : {"10", "0-10", "9-10", "0-1000000000000", "4,18446744073709551615"}) {
    try {
      ParseFrameList(beyond, 10);
      ADD_FAILURE() << beyond;
    } catch (const InvalidArgument& e) {
      EXPECT_NE(std::string(e.what()).find("its frames are 0 to 9"), std::string::npos) << e.what();
    }
  }
}

TEST(ComposeFrames, BlacksOutComposedPositionsNotSourceFrames) {
  const auto composed = ComposeFrames({5, 6, 7, 6, 5}, 2, 4);
  ASSERT_EQ(composed.size(), 5u);
  EXPECT_EQ(composed[3].source_frame, 6u);
  EXPECT_FALSE(composed[1].black);
  EXPECT_TRUE(composed[2].black);
  EXPECT_TRUE(composed[3].black);
  EXPECT_FALSE(composed[4].black);
}

TEST(WriteComposedSequence, KittiForthAndBackWithTruthAndABlackFrame) {
  SEMSLAM_REQUIRE_SHARED_DATA(data, "kitti_odom_07_3dv");
  const auto source = OpenSequence(data / "sequences/07");
  testing::TempDir dir;
  const std::vector<size_t> frames = {10, 11, 12, 11, 10};
  WriteComposedSequence(*source, ComposeFrames(frames, 4, 5), dir / "composed", /*stereo=*/false);

  const auto composed = OpenSequence(dir / "composed");
  ASSERT_EQ(composed->size(), frames.size());
  EXPECT_EQ(composed->camera().fx, source->camera().fx);
  // Evenly spaced at the source's frame rate, starting at 0.
  EXPECT_DOUBLE_EQ(composed->Timestamp(0), 0.0);
  EXPECT_NEAR(composed->Timestamp(4), 4 * (source->Timestamp(11) - source->Timestamp(10)), 0.01);
  // Frame 3 is source frame 11 again; frame 4 is black.
  const cv::Mat again = composed->LoadImage(3), original = source->LoadImage(11);
  ASSERT_EQ(again.size(), original.size());
  EXPECT_EQ(cv::norm(again, original, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::countNonZero(composed->LoadImage(4)), 0);
  // The truth is the source's, in the source's frame (drives composed from one source share it): frame 3 sits
  // where frame 1 does, and each composed frame where its source frame does.
  const std::optional<Trajectory> truth = composed->GroundTruth();
  ASSERT_TRUE(truth.has_value());
  ASSERT_EQ(truth->size(), frames.size());
  EXPECT_LT(((*truth)[3].world_from_camera.translation - (*truth)[1].world_from_camera.translation).norm(), 1e-6);
  const Trajectory source_truth = *source->GroundTruth();
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_LT(((*truth)[i].world_from_camera.translation - source_truth[frames[i]].world_from_camera.translation)
                  .norm(),
              1e-6)
        << "composed frame " << i;
  }
  const double step = (source_truth[12].world_from_camera.translation -
                       source_truth[10].world_from_camera.translation).norm();
  EXPECT_GT(step, 0.1);  // the car moves, so frame 10's place is not frame 0's
  EXPECT_GT(truth->front().world_from_camera.translation.norm(), 0.1);

  // A cut (frames left out) leaves a gap in time, as dropped frames do.
  WriteComposedSequence(*source, ComposeFrames({10, 11, 16}), dir / "cut", false);
  const auto cut = OpenSequence(dir / "cut");
  EXPECT_NEAR(cut->Timestamp(2) - cut->Timestamp(1), 5 * (cut->Timestamp(1) - cut->Timestamp(0)), 1e-3);

  // Frames the source does not have, and a folder already in use, are refused.
  try {
    WriteComposedSequence(*source, ComposeFrames({1000}), dir / "other", false);
    ADD_FAILURE() << "frame 1000 of a 160-frame sequence was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no frame 1000 (its frames are 0 to 159)"), std::string::npos) << e.what();
  }
  EXPECT_THROW(WriteComposedSequence(*source, ComposeFrames({1}), dir / "composed", false), InputError);
  std::ofstream(dir / "afile") << "x";
  try {
    WriteComposedSequence(*source, ComposeFrames({1}), dir / "afile", false);
    ADD_FAILURE() << "a file taken as the output folder";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("is a file"), std::string::npos) << e.what();
  }
}

// A three-frame image folder with per-frame labels (8 bit) and depth (16 bit), as the synthetic city has.
std::filesystem::path WriteLabelledSource(const std::filesystem::path& dir) {
  for (const char* sub : {"images", "labels", "depth"}) std::filesystem::create_directories(dir / sub);
  for (int i = 0; i < 3; ++i) {
    const std::string name = fmt::format("{:06d}.png", i);
    WritePng(dir / "images" / name, cv::Mat(48, 64, CV_8UC1, cv::Scalar(50 + i)));
    WritePng(dir / "labels" / name, cv::Mat(48, 64, CV_8UC1, cv::Scalar(i)));  // road, sidewalk, building
    WritePng(dir / "depth" / name, cv::Mat(48, 64, CV_16UC1, cv::Scalar(1000 + 300 * i)));
  }
  CameraYaml yaml;
  yaml.camera = {.width = 64, .height = 48, .fx = 50, .fy = 50, .cx = 32, .cy = 24};
  yaml.images = dir / "images";
  yaml.labels = dir / "labels";
  yaml.depth = dir / "depth";
  WriteCameraYaml(dir / "camera.yaml", yaml);
  return dir;
}

cv::Mat ReadUnchanged(const std::filesystem::path& path) {
  return cv::imread(path.string(), cv::IMREAD_UNCHANGED);
}

TEST(WriteComposedSequence, LabelsAndDepthGoAlongAndABlackFrameHasNone) {
  testing::TempDir dir;
  const auto source = OpenSequence(WriteLabelledSource(dir / "source"));
  ASSERT_TRUE(source->LabelDirectory().has_value());
  WriteComposedSequence(*source, ComposeFrames({2, 1, 0}, 1, 2), dir / "composed", /*stereo=*/false);

  const auto composed = OpenSequence(dir / "composed");
  ASSERT_TRUE(composed->LabelDirectory().has_value());
  ASSERT_TRUE(composed->DepthDirectory().has_value());
  // Composed frame 0 is source frame 2: its labels and depth, unchanged (depth stays 16 bit).
  const cv::Mat label0 = ReadUnchanged(*composed->LabelDirectory() / "000000.png");
  const cv::Mat depth0 = ReadUnchanged(*composed->DepthDirectory() / "000000.png");
  ASSERT_EQ(label0.type(), CV_8UC1);
  ASSERT_EQ(depth0.type(), CV_16UC1);
  EXPECT_EQ(label0.at<std::uint8_t>(10, 10), 2);
  EXPECT_EQ(depth0.at<std::uint16_t>(10, 10), 1600);
  // Frame 1 is black: nothing seen, so no label (255, Cityscapes' ignore id) and no depth.
  const cv::Mat label1 = ReadUnchanged(*composed->LabelDirectory() / "000001.png");
  EXPECT_EQ(cv::countNonZero(cv::Mat(label1 != 255)), 0);
  EXPECT_EQ(cv::countNonZero(ReadUnchanged(*composed->DepthDirectory() / "000001.png")), 0);
  EXPECT_EQ(ReadUnchanged(*composed->LabelDirectory() / "000002.png").at<std::uint8_t>(0, 0), 0);

  // A source frame without its label image is refused, naming the file.
  std::filesystem::remove(dir / "source" / "labels" / "000001.png");
  try {
    WriteComposedSequence(*source, ComposeFrames({0, 1}), dir / "missing", false);
    ADD_FAILURE() << "a frame without its label image was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("000001.png"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("label image of frame 1 is missing"), std::string::npos) << e.what();
  }
  // Nothing is left of a compose that failed half-way: a new folder is gone, an empty one empty again.
  EXPECT_FALSE(std::filesystem::exists(dir / "missing"));
  std::filesystem::create_directories(dir / "empty");
  EXPECT_THROW(WriteComposedSequence(*source, ComposeFrames({0, 1}), dir / "empty", false), InputError);
  EXPECT_TRUE(std::filesystem::is_directory(dir / "empty"));
  EXPECT_TRUE(std::filesystem::is_empty(dir / "empty"));
}

TEST(WriteComposedSequence, AnInterruptionStopsItAndLeavesNothing) {
  testing::TempDir dir;
  const auto source = OpenSequence(WriteLabelledSource(dir / "source"));
  RequestInterrupt(SIGINT);
  EXPECT_THROW(WriteComposedSequence(*source, ComposeFrames({0, 1, 2}), dir / "composed", false),
               Interrupted);
  ClearInterrupt();
  EXPECT_FALSE(std::filesystem::exists(dir / "composed"));
}

}  // namespace
}  // namespace semslam
