#include "semslam/io/sequence_composer.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <string>

#include "semslam/core/error.h"
#include "semslam/io/sequence.h"
#include "support/test_support.h"

namespace semslam {
namespace {

TEST(ParseFrameList, RangesRunBothWaysAndSingleFramesStayPut) {
  EXPECT_EQ(ParseFrameList("0-3"), (std::vector<size_t>{0, 1, 2, 3}));
  EXPECT_EQ(ParseFrameList("3-1,7,0-0"), (std::vector<size_t>{3, 2, 1, 7, 0}));
  for (const char* bad : {"", "1,", ",1", "1-", "a-3", "1-2-3", "-1", "1;2"}) {
    EXPECT_THROW(ParseFrameList(bad), InvalidArgument) << bad;
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
  // The truth is the source's, relative to the first composed frame: frame 3 sits where frame 1 does.
  const std::optional<Trajectory> truth = composed->GroundTruth();
  ASSERT_TRUE(truth.has_value());
  ASSERT_EQ(truth->size(), frames.size());
  EXPECT_LT(truth->front().world_from_camera.translation.norm(), 1e-9);
  EXPECT_LT(((*truth)[3].world_from_camera.translation - (*truth)[1].world_from_camera.translation).norm(), 1e-6);
  const Trajectory source_truth = *source->GroundTruth();
  const double step = (source_truth[12].world_from_camera.translation -
                       source_truth[10].world_from_camera.translation).norm();
  EXPECT_GT(step, 0.1);  // the car moves
  EXPECT_NEAR((*truth)[2].world_from_camera.translation.norm(), step, 1e-6);

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
}

}  // namespace
}  // namespace semslam
