#pragma once
// Trajectory files: TUM ("t tx ty tz qx qy qz qw" per line, '#' comments) and KITTI (12 numbers per line,
// the row-major [R|t] of world_from_camera, no timestamps).

#include <filesystem>
#include <optional>
#include <vector>

#include "semslam/geometry/trajectory.h"

namespace semslam {

Trajectory ReadTumTrajectory(const std::filesystem::path& path);
void WriteTumTrajectory(const std::filesystem::path& path, const Trajectory& trajectory);

std::vector<Rigid3d> ReadKittiPoses(const std::filesystem::path& path);
void WriteKittiPoses(const std::filesystem::path& path, const std::vector<Rigid3d>& world_from_camera);
void WriteKittiPoses(const std::filesystem::path& path, const Trajectory& trajectory);

// KITTI times.txt: one timestamp (seconds) per line.
std::vector<double> ReadTimes(const std::filesystem::path& path);
void WriteTimes(const std::filesystem::path& path, const std::vector<double>& timestamps);

enum class TrajectoryFormat { kTum, kKitti };
// Decides by the number of columns of the first data line (8: TUM, 12: KITTI).
TrajectoryFormat DetectTrajectoryFormat(const std::filesystem::path& path);

// Reads either format. KITTI poses get timestamps from `times` when given (it may list more stamps than
// poses), otherwise the line index.
Trajectory ReadTrajectory(const std::filesystem::path& path,
                          const std::optional<std::filesystem::path>& times = std::nullopt);

}  // namespace semslam
