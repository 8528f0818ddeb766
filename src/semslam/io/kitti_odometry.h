#pragma once
// KITTI odometry layout: sequences/XX/{image_0,image_1}/%06d.png, calib.txt (P0..P3, optional Tr),
// times.txt, and poses/XX.txt two levels up.

#include <array>
#include <filesystem>
#include <optional>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/eigen_types.h"
#include "semslam/io/sequence.h"

namespace semslam {

struct KittiCalibration {
  // P0..P3; rows missing from the file stay zero.
  std::array<Eigen::Matrix3x4d, 4> projection{Eigen::Matrix3x4d::Zero(), Eigen::Matrix3x4d::Zero(),
                                              Eigen::Matrix3x4d::Zero(), Eigen::Matrix3x4d::Zero()};
  int num_projections = 0;                       // how many P rows the file had (at least 1)
  std::optional<Eigen::Matrix3x4d> velo_to_cam;  // "Tr", when present

  // Left grey camera (P0) at the given image size.
  PinholeCamera Camera0(int width, int height) const;
  // Rectified stereo rig P0/P1; nullopt if P1 is missing. Baseline = -P1(0,3) / P1(0,0) (relative to P0).
  std::optional<StereoRig> Stereo01(int width, int height) const;
};

KittiCalibration ReadKittiCalibration(const std::filesystem::path& path);
void WriteKittiCalibration(const std::filesystem::path& path, const KittiCalibration& calibration);
// P0..P3 of a rectified rig: grey pair (0, 1) and colour pair (2, 3) share the intrinsics here.
KittiCalibration MakeKittiCalibration(const StereoRig& rig);

// Opens a KITTI odometry sequence folder (the one holding image_0/). Ground truth is looked up in
// `../../poses/<name>.txt` relative to it, when present.
std::unique_ptr<ImageSequence> OpenKittiOdometry(const std::filesystem::path& sequence_dir);

}  // namespace semslam
