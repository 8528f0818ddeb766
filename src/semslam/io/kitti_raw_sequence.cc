// The KITTI raw drive as an ImageSequence, and the drive's calibration chain.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <system_error>

#include "semslam/core/error.h"
#include "semslam/io/kitti_odometry.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/sequence_internal.h"

namespace semslam {

namespace fs = std::filesystem;

fs::path FindKittiRawCalibFile(const fs::path& drive_dir, const std::string& file_name) {
  const fs::path dir = io_internal::NormalizeDirectory(drive_dir);
  std::error_code ec;
  for (const fs::path& candidate : {dir / file_name, dir.parent_path() / file_name}) {
    if (fs::is_regular_file(candidate, ec)) return candidate;
  }
  throw InputError(dir / file_name, fmt::format("not found, neither in the drive folder nor in its parent {}",
                                                dir.parent_path().string()));
}

namespace {

Eigen::Matrix3x4d Matrix3x4(const std::vector<double>& values) {
  Eigen::Matrix3x4d m;
  for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = values[static_cast<size_t>(i)];
  return m;
}

SourceLocation LineOf(const KittiRawCalibFile& calib, const std::string& key) {
  const auto line = calib.lines.find(key);
  return SourceLocation{calib.file, line == calib.lines.end() ? 0 : line->second};
}

// P_rect_0X of calib_cam_to_cam.txt, checked to be a rectified projection K [I | t].
Eigen::Matrix3x4d RectifiedProjection(const KittiRawCalibFile& calib, int camera_index) {
  const std::string key = fmt::format("P_rect_0{}", camera_index);
  const Eigen::Matrix3x4d p = Matrix3x4(calib.Get(key, 12));
  if (!(p(0, 0) > 0) || !(p(1, 1) > 0))
    throw InputError(LineOf(calib, key), key, "focal lengths must be positive");
  if (p(2, 0) != 0 || p(2, 1) != 0 || std::abs(p(2, 2) - 1.0) > 1e-9) {
    throw InputError(LineOf(calib, key), key, "the third row must start with 0 0 1 (a rectified projection)");
  }
  return p;
}

std::string CamerasPresent(const fs::path& dir) {
  std::string list;
  std::error_code ec;
  for (int i = 0; i < 4; ++i) {
    const std::string name = fmt::format("image_0{}", i);
    if (fs::is_directory(dir / name / "data", ec)) list += (list.empty() ? "" : ", ") + name;
  }
  return list.empty() ? "none" : list;
}

}  // namespace

Rigid3d ReadKittiRawRectifiedCameraFromVelo(const fs::path& drive_dir, int camera_index) {
  Require(camera_index >= 0 && camera_index <= 3, "ReadKittiRawRectifiedCameraFromVelo: cameras are 0..3");
  const Rigid3d cam0_from_velo = ReadKittiRawRigid(FindKittiRawCalibFile(drive_dir, "calib_velo_to_cam.txt"));
  const KittiRawCalibFile cam =
      ReadKittiRawCalibFile(FindKittiRawCalibFile(drive_dir, "calib_cam_to_cam.txt"));
  Eigen::Matrix3x4d m = Eigen::Matrix3x4d::Zero();
  m.leftCols<3>() = cam.GetRotation("R_rect_00");
  const Rigid3d rect_from_cam0 = Rigid3d::FromMatrix(m);
  const Rigid3d camera_from_rect(Eigen::Quaterniond::Identity(),
                                 ProjectionOffset(RectifiedProjection(cam, camera_index)));
  return camera_from_rect * rect_from_cam0 * cam0_from_velo;
}

Rigid3d ReadKittiRawRectifiedCameraFromImu(const fs::path& drive_dir, int camera_index) {
  const Rigid3d velo_from_imu = ReadKittiRawRigid(FindKittiRawCalibFile(drive_dir, "calib_imu_to_velo.txt"));
  return ReadKittiRawRectifiedCameraFromVelo(drive_dir, camera_index) * velo_from_imu;
}

std::unique_ptr<ImageSequence> OpenKittiRaw(const fs::path& drive_dir, const SequenceOptions& options) {
  io_internal::SequenceFiles files;
  files.directory = io_internal::NormalizeDirectory(drive_dir);
  const fs::path& dir = files.directory;
  files.name = dir.filename().string();
  const io_internal::KittiCamera chosen = io_internal::ChooseKittiCamera(dir, options, /*raw=*/true);
  files.camera_name = chosen.name;
  std::error_code ec;
  const fs::path images = dir / chosen.name / "data";
  if (!fs::is_directory(images, ec)) {
    throw InputError(images,
                     fmt::format("folder not found (a KITTI raw drive has {}/data/%010d.png for camera "
                                 "{}; cameras with images here: {})",
                                 chosen.name, chosen.name, CamerasPresent(dir)));
  }
  files.left = io_internal::NumberedFiles(images, 10, ".png");
  const size_t n = files.left.size();

  const fs::path stamps_file = dir / chosen.name / "timestamps.txt";
  const std::vector<double> stamps = ReadKittiRawTimestamps(stamps_file);
  if (stamps.size() < n) {
    throw InputError(stamps_file, fmt::format("lists {} timestamps, fewer than the {} images in {}/data/",
                                              stamps.size(), n, chosen.name));
  }
  for (size_t i = 1; i < n; ++i) {
    if (!(stamps[i] > stamps[i - 1])) {
      throw InputError(SourceLocation{stamps_file, static_cast<int>(i + 1)}, "timestamp",
                       "not after the previous one (frames need increasing timestamps)");
    }
  }
  files.timestamps.assign(stamps.begin(), stamps.begin() + static_cast<std::ptrdiff_t>(n));

  const KittiRawCalibFile calib = ReadKittiRawCalibFile(FindKittiRawCalibFile(dir, "calib_cam_to_cam.txt"));
  const std::string p_key = fmt::format("P_rect_0{}", chosen.index);
  const std::string s_key = fmt::format("S_rect_0{}", chosen.index);
  const Eigen::Matrix3x4d p = RectifiedProjection(calib, chosen.index);
  const std::vector<double> size = calib.Get(s_key, 2);
  files.camera.fx = p(0, 0);
  files.camera.fy = p(1, 1);
  files.camera.cx = p(0, 2);
  files.camera.cy = p(1, 2);
  files.calibration = calib.file;
  files.camera.width = static_cast<int>(std::lround(size[0]));
  files.camera.height = static_cast<int>(std::lround(size[1]));
  if (!(files.camera.width > 0) || !(files.camera.height > 0)) {
    throw InputError(LineOf(calib, s_key), s_key, "image size must be positive");
  }

  if (chosen.right_name) {
    const fs::path right_images = dir / *chosen.right_name / "data";
    if (fs::is_directory(right_images, ec)) {
      const int right_index = chosen.index + 1;
      const std::string right_key = fmt::format("P_rect_0{}", right_index);
      const Eigen::Matrix3x4d p_right = RectifiedProjection(calib, right_index);
      if ((p_right.leftCols<3>() - p.leftCols<3>()).cwiseAbs().maxCoeff() > 1e-6 * p(0, 0)) {
        throw InputError(LineOf(calib, right_key), right_key,
                         fmt::format("intrinsics differ from {}'s: not a rectified stereo pair", p_key));
      }
      const double baseline = ProjectionOffset(p).x() - ProjectionOffset(p_right).x();
      if (!(baseline > 0)) {
        throw InputError(LineOf(calib, right_key), right_key,
                         fmt::format("gives baseline {} m; expected a positive one", baseline));
      }
      const size_t right_count = io_internal::ListFiles(right_images, {".png"}).size();
      if (right_count < n) {
        throw InputError(right_images, fmt::format("holds {} images, fewer than the {} in {}/data/",
                                                   right_count, n, chosen.name));
      }
      for (size_t i = 0; i < n; ++i) files.right.push_back(right_images / files.left[i].filename());
      files.baseline = baseline;
    } else if (options.stereo) {
      throw InputError(right_images, fmt::format("folder not found: stereo with camera {} needs its right "
                                                 "camera {}",
                                                 chosen.name, *chosen.right_name));
    }
  }

  if (fs::is_directory(dir / "oxts", ec)) {
    const std::vector<StampedOxts> readings = ReadOxtsFolder(dir / "oxts");
    std::vector<OxtsRecord> records;
    for (size_t i = 0; i < std::min(n, readings.size()); ++i) records.push_back(readings[i].record);
    if (records.size() < n) {
      spdlog::warn("{}: {} readings for {} frames: ground truth for the first {} frames only",
                   (dir / "oxts").string(), records.size(), n, records.size());
    }
    const Rigid3d camera_from_imu = ReadKittiRawRectifiedCameraFromImu(dir, chosen.index);
    files.gps_antenna_in_camera = camera_from_imu.translation;  // the OXTS unit gives the IMU's position
    const std::vector<Rigid3d> poses = OxtsCameraPoses(records, camera_from_imu);
    Trajectory truth;
    truth.reserve(poses.size());
    for (size_t i = 0; i < poses.size(); ++i) truth.push_back({files.timestamps[i], poses[i]});
    if (!truth.empty()) files.ground_truth = std::move(truth);
  }
  return io_internal::MakeFileSequence(std::move(files));
}

}  // namespace semslam
