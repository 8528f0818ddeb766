#pragma once
// trajectory.kitti: one pose per frame of a run. KITTI pose files carry no timestamps (evo and the KITTI
// devkit pair line i with frame i), so a frame without its own pose still gets a line: the best pose known
// for it (io/trajectory_io.h FillFrameGaps).

#include <cstddef>
#include <filesystem>
#include <span>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/io/trajectory_io.h"

namespace semslam {

// The frames' own poses in the map the trajectory is written in, in frame order.
std::vector<IndexedPose> MapFramePoses(const std::vector<FramePose>& frames);

// Writes one line per frame of [first_frame, end_frame) to `path` and returns where each pose came from;
// `times`: those frames' timestamps (see FillFrameGaps).
DenseTrajectory WriteKittiFrameTrajectory(const std::filesystem::path& path,
                                          const std::vector<FramePose>& frames, size_t first_frame,
                                          size_t end_frame, std::span<const double> times);

}  // namespace semslam
