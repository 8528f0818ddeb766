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

  // Camera `index` (P<index>, 0..3) at the given image size.
  PinholeCamera Camera(int index, int width, int height) const;
  // The translation t of P<index> = K [I | t]: camera `index` from camera 0 (the rectified cameras share
  // their orientation), metres. Zero for P0; (-baseline, 0, 0) for P1.
  Eigen::Vector3d Offset(int index) const;
  // Rectified stereo rig P<left>/P<left+1> (left 0 or 2); nullopt if P<left+1> is missing. Baseline: the
  // difference of the two cameras' x offsets (-P1(0,3) / P1(0,0) for the pair 0/1).
  std::optional<StereoRig> Stereo(int left, int width, int height) const;

  PinholeCamera Camera0(int width, int height) const { return Camera(0, width, height); }
  std::optional<StereoRig> Stereo01(int width, int height) const { return Stereo(0, width, height); }
};

KittiCalibration ReadKittiCalibration(const std::filesystem::path& path);
// The translation t of a rectified projection P = K [I | t] (K upper triangular, P(2,0:3) = 0 0 1).
Eigen::Vector3d ProjectionOffset(const Eigen::Matrix3x4d& projection);
void WriteKittiCalibration(const std::filesystem::path& path, const KittiCalibration& calibration);
// P0..P3 of a rectified rig: grey pair (0, 1) and colour pair (2, 3) share the intrinsics here.
KittiCalibration MakeKittiCalibration(const StereoRig& rig);

// Opens a KITTI odometry sequence folder (the one holding image_0/), reading the camera `options` chooses
// (image_0 by default; image_2 with image_3 for stereo, and so on) with its P row of calib.txt. Ground truth
// is looked up in `../../poses/<name>.txt` relative to it, when present; the poses there are camera 0's,
// moved to the chosen camera by its offset (KittiCalibration::Offset).
std::unique_ptr<ImageSequence> OpenKittiOdometry(const std::filesystem::path& sequence_dir,
                                                 const SequenceOptions& options = {});

}  // namespace semslam
