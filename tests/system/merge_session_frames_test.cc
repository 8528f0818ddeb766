// Where a merge puts a drive's frames (system/merge_session_frames.h): each follows its keyframe, its offset
// from it stretched as the map around the keyframe was.

#include "semslam/system/merge_session_frames.h"

#include <gtest/gtest.h>

#include "map/map_test_frames.h"
#include "semslam/map/map.h"
#include "semslam/system/atlas_outputs.h"
#include "support/test_support.h"

namespace semslam {
namespace {

// A drive along z at 1 m per 10 frames, a keyframe every 10 frames (0..50) and frames 0..59 tracked from
// them; then the map is stretched by 1.1 around its origin as a monocular merge's adjustment may, while the
// keyframes' own scale (KeyFrame::scale_correction) is left as it was.
class StretchedDrive : public ::testing::Test {
 protected:
  void SetUp() override {
    auto lock = map_.WriteLock();
    std::vector<FramePose> frames;
    for (std::uint64_t f = 0; f < 60; ++f) {
      const Eigen::Vector3d center(0.0, 0.0, 0.1 * static_cast<double>(f));
      frames.push_back(
          {f, -1, 0.1 * static_cast<double>(f), Rigid3d(Eigen::Quaterniond::Identity(), center), 0, false});
      if (f % 10 != 0) continue;
      KeyFrame* kf = map_.AddKeyFrame(MakeFrame(f, 10, /*stereo=*/false, center));
      record_.anchors[0][f] = {kf, kf->world_from_camera(), kf->scale_correction()};
    }
    record_.input = InputSession{};
    record_.input->frames_csv = dir_.path() / "frames.csv";
    WriteFramesCsv(record_.input->frames_csv, frames, 0);
    for (KeyFrame* kf : map_.KeyFrames())
      kf->SetPose(Rigid3d(Eigen::Quaterniond::Identity(), -kStretch * kf->world_from_camera().translation));
  }

  static constexpr double kStretch = 1.1;
  testing::TempDir dir_;
  Map map_;
  SessionRecord record_;
};

TEST_F(StretchedDrive, FramesStretchWithTheSpacingOfTheirKeyFrames) {
  auto lock = map_.ReadLock();
  const std::vector<FramePose> frames = SessionFrames(record_, FrameScale::kNeighbourSpacing, nullptr);
  ASSERT_EQ(frames.size(), 60u);
  for (const FramePose& f : frames) {
    // Frame 59 follows keyframe 50 (the drive's last) over 0.9 m: 0.99 m after the stretch.
    EXPECT_NEAR(f.world_from_camera.translation.z(), kStretch * 0.1 * static_cast<double>(f.frame_index),
                1e-9)
        << f.frame_index;
  }
}

TEST_F(StretchedDrive, FramesKeepTheirOffsetWhenTheyFollowTheKeyFramesOwnScale) {
  // Stereo: the keyframes carry the scale (none here), and the offset stays metric.
  auto lock = map_.ReadLock();
  const std::vector<FramePose> frames = SessionFrames(record_, FrameScale::kKeyFrame, nullptr);
  ASSERT_EQ(frames.size(), 60u);
  EXPECT_NEAR(frames.back().world_from_camera.translation.z(), kStretch * 5.0 + 0.9, 1e-9);
}

TEST_F(StretchedDrive, AKeyFrameLostInTheMergeHandsItsFramesToTheNearestOne) {
  {
    auto lock = map_.WriteLock();
    KeyFrame* last = record_.anchors[0].at(50).keyframe;
    last->SetBad();
    map_.EraseKeyFrame(last);
  }
  auto lock = map_.ReadLock();
  size_t unanchored = 0;
  const std::vector<FramePose> frames = SessionFrames(record_, FrameScale::kNeighbourSpacing, &unanchored);
  ASSERT_EQ(frames.size(), 60u);
  EXPECT_EQ(unanchored, 0u);
  // Frames 41-59 now follow keyframe 40, stretched as its spacing to keyframes 10-30 was.
  EXPECT_NEAR(frames.back().world_from_camera.translation.z(), kStretch * 5.9, 1e-9);
}

}  // namespace
}  // namespace semslam
