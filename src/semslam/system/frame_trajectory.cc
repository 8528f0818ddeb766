#include "semslam/system/frame_trajectory.h"

#include <spdlog/spdlog.h>

namespace semslam {

std::vector<IndexedPose> MapFramePoses(const std::vector<FramePose>& frames) {
  // SlamSystem::FramePoses() gives only frames in the main map of the atlas: frames of a map never merged
  // into it are in another frame, so their lines are filled like those of untracked frames (frames.csv marks
  // them).
  std::vector<IndexedPose> poses;
  poses.reserve(frames.size());
  for (const FramePose& frame : frames) poses.push_back({frame.frame_index, frame.world_from_camera});
  return poses;
}

DenseTrajectory WriteKittiFrameTrajectory(const std::filesystem::path& path,
                                          const std::vector<FramePose>& frames, size_t first_frame,
                                          size_t end_frame, std::span<const double> times) {
  DenseTrajectory dense = FillFrameGaps(MapFramePoses(frames), first_frame, end_frame, {}, times);
  WriteKittiPoses(path, dense.world_from_camera);
  const size_t own = dense.Count(PoseSource::kEstimated);
  if (own == 0) {
    spdlog::warn("{}: no frame was tracked; every line is the identity", path.filename().string());
  } else if (own < dense.source.size()) {
    spdlog::info(
        "{}: {} of {} frames have their own pose; {} before the first take its pose, {} are bridged "
        "between tracked frames, {} after the last predicted by the motion model, {} held",
        path.filename().string(), own, dense.source.size(), dense.Count(PoseSource::kFirstPose),
        dense.Count(PoseSource::kInterpolated), dense.Count(PoseSource::kMotionModel),
        dense.Count(PoseSource::kHeld));
  }
  return dense;
}

}  // namespace semslam
