#pragma once
// Trajectory files: TUM ("t tx ty tz qx qy qz qw" per line, '#' comments) and KITTI (12 numbers per line,
// the row-major [R|t] of world_from_camera, no timestamps).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <vector>

#include "semslam/geometry/trajectory.h"

namespace semslam {

Trajectory ReadTumTrajectory(const std::filesystem::path& path);
void WriteTumTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);

std::vector<Rigid3d> ReadKittiPoses(const std::filesystem::path& path);
// The number of poses (data lines) in a KITTI pose file, without parsing them.
size_t CountKittiPoses(const std::filesystem::path& path);
void WriteKittiPoses(const std::filesystem::path& path, const std::vector<Rigid3d>& world_from_camera);
void WriteKittiPoses(const std::filesystem::path& path, const Trajectory& trajectory);

// KITTI times.txt: one timestamp (seconds) per line.
std::vector<double> ReadTimes(const std::filesystem::path& path);
void WriteTimes(const std::filesystem::path& path, const std::vector<double>& timestamps);

// ---- One pose per frame (KITTI pairs line i with frame i, so a frame without a pose cannot be left out) ----

// A pose estimated for one frame of a sequence.
struct IndexedPose {
  size_t frame_index = 0;
  Rigid3d world_from_camera;
};

// Where a frame's pose in a dense trajectory comes from.
enum class PoseSource : std::uint8_t {
  kEstimated,     // the frame's own pose (it was tracked)
  kFirstPose,     // before the first estimated frame: that frame's pose
  kMotionModel,   // after the last estimated frame: the constant-velocity prediction of the two before it
  kHeld,          // longer trailing gaps: the last prediction (no velocity known: the last pose), held
  kInterpolated,  // between two estimated frames: bridged from both ends (DenseTrajectoryOptions)
  kNone,          // no frame was estimated at all: the identity (the world is the first camera's frame)
};

struct DenseTrajectoryOptions {
  // Frames after the last estimated one that are predicted by the motion model before the pose is held; the
  // prediction drifts quickly once the vehicle turns or brakes.
  int max_predicted_frames = 10;
  // A gap between two estimated frames of up to this many frames is bridged by the motion its ends' velocities
  // give, changing steadily from one to the other, carried from both ends and blended (exact for steady motion,
  // a turn included, and for steady acceleration); a longer one by the geodesic between the ends, as the ends'
  // velocities over a longer span go astray.
  int max_velocity_bridge_frames = 50;
  void Check() const;  // throws InvalidArgument
};

struct DenseTrajectory {
  size_t first_frame = 0;                  // world_from_camera[i] is frame first_frame + i
  std::vector<Rigid3d> world_from_camera;  // one per frame of [first, end)
  std::vector<PoseSource> source;          // one per frame
  size_t Count(PoseSource what) const;
};

// A pose for every frame of [first_frame, end_frame) from the estimated ones (strictly increasing frame
// indices; those outside the range are ignored), the gaps filled as PoseSource says. Motion is carried in
// time: `times` holds the timestamps of the frames of the range (a camera that dropped frames jumps in time);
// empty, the frames are evenly spaced. Throws InvalidArgument when first_frame > end_frame, the poses are not
// in order, or the times are not one per frame, increasing.
DenseTrajectory FillFrameGaps(const std::vector<IndexedPose>& estimated, size_t first_frame, size_t end_frame,
                              const DenseTrajectoryOptions& options = {}, std::span<const double> times = {});

enum class TrajectoryFormat { kTum, kKitti };
// Decides by the number of columns of the first data line (8: TUM, 12: KITTI).
TrajectoryFormat DetectTrajectoryFormat(const std::filesystem::path& path);

// Reads either format. KITTI poses get timestamps from `times` when given (it may list more stamps than
// poses), otherwise the line index.
Trajectory ReadTrajectory(const std::filesystem::path& path,
                          const std::optional<std::filesystem::path>& times = std::nullopt);

}  // namespace semslam
