// The KITTI raw drive as an ImageSequence, and the drive's calibration chain.

#include <fmt/format.h>

#include <cmath>
#include <system_error>

#include "semslam/core/error.h"
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

Rigid3d ReadKittiRawRectifiedCam0FromImu(const fs::path& drive_dir) {
  const Rigid3d velo_from_imu = ReadKittiRawRigid(FindKittiRawCalibFile(drive_dir, "calib_imu_to_velo.txt"));
  const Rigid3d cam0_from_velo = ReadKittiRawRigid(FindKittiRawCalibFile(drive_dir, "calib_velo_to_cam.txt"));
  const KittiRawCalibFile cam =
      ReadKittiRawCalibFile(FindKittiRawCalibFile(drive_dir, "calib_cam_to_cam.txt"));
  const std::vector<double> r = cam.Get("R_rect_00", 9);
  Eigen::Matrix3x4d m = Eigen::Matrix3x4d::Zero();
  for (int i = 0; i < 9; ++i) m(i / 3, i % 3) = r[i];
  const Rigid3d rect_from_cam0 = Rigid3d::FromMatrix(m);
  return rect_from_cam0 * cam0_from_velo * velo_from_imu;
}

std::unique_ptr<ImageSequence> OpenKittiRaw(const fs::path& drive_dir) {
  io_internal::SequenceFiles files;
  files.directory = io_internal::NormalizeDirectory(drive_dir);
  const fs::path& dir = files.directory;
  files.name = dir.filename().string();
  std::error_code ec;
  if (!fs::is_directory(dir / "image_00" / "data", ec)) {
    throw InputError(dir / "image_00" / "data",
                     "folder not found (a KITTI raw drive has image_00/data/%010d.png)");
  }
  files.left = io_internal::NumberedFiles(dir / "image_00" / "data", 10, ".png");
  const size_t n = files.left.size();

  const fs::path stamps_file = dir / "image_00" / "timestamps.txt";
  const std::vector<double> stamps = ReadKittiRawTimestamps(stamps_file);
  if (stamps.size() < n) {
    throw InputError(
        stamps_file,
        fmt::format("lists {} timestamps, fewer than the {} images in image_00/data/", stamps.size(), n));
  }
  for (size_t i = 1; i < n; ++i) {
    if (!(stamps[i] > stamps[i - 1])) {
      throw InputError(SourceLocation{stamps_file, static_cast<int>(i + 1)}, "timestamp",
                       "not after the previous one (frames need increasing timestamps)");
    }
  }
  files.timestamps.assign(stamps.begin(), stamps.begin() + static_cast<std::ptrdiff_t>(n));

  const KittiRawCalibFile calib = ReadKittiRawCalibFile(FindKittiRawCalibFile(dir, "calib_cam_to_cam.txt"));
  const std::vector<double> p0 = calib.Get("P_rect_00", 12);
  const std::vector<double> size = calib.Get("S_rect_00", 2);
  files.camera.fx = p0[0];
  files.camera.fy = p0[5];
  files.camera.cx = p0[2];
  files.camera.cy = p0[6];
  files.calibration = calib.file;
  files.camera.width = static_cast<int>(std::lround(size[0]));
  files.camera.height = static_cast<int>(std::lround(size[1]));
  const SourceLocation p0_at{calib.file, calib.lines.at("P_rect_00")};
  if (!(p0[0] > 0) || !(p0[5] > 0)) throw InputError(p0_at, "P_rect_00", "focal lengths must be positive");
  if (!(files.camera.width > 0) || !(files.camera.height > 0)) {
    throw InputError(SourceLocation{calib.file, calib.lines.at("S_rect_00")}, "S_rect_00",
                     "image size must be positive");
  }

  if (fs::is_directory(dir / "image_01" / "data", ec)) {
    const std::vector<double> p1 = calib.Get("P_rect_01", 12);
    const SourceLocation p1_at{calib.file, calib.lines.at("P_rect_01")};
    const double baseline = -p1[3] / p1[0];
    if (std::abs(p1[0] - p0[0]) > 1e-6 * p0[0] || std::abs(p1[5] - p0[5]) > 1e-6 * p0[5] ||
        std::abs(p1[2] - p0[2]) > 1e-6 * p0[0] || std::abs(p1[6] - p0[6]) > 1e-6 * p0[0]) {
      throw InputError(p1_at, "P_rect_01", "intrinsics differ from P_rect_00's: not a rectified stereo pair");
    }
    if (!(baseline > 0)) {
      throw InputError(p1_at, "P_rect_01",
                       fmt::format("gives baseline {} m; expected a positive one", baseline));
    }
    const size_t right_count = io_internal::ListFiles(dir / "image_01" / "data", {".png"}).size();
    if (right_count < n) {
      throw InputError(dir / "image_01" / "data",
                       fmt::format("holds {} images, fewer than the {} in image_00/data/", right_count, n));
    }
    for (size_t i = 0; i < n; ++i)
      files.right.push_back(dir / "image_01" / "data" / files.left[i].filename());
    files.baseline = baseline;
  }
  return io_internal::MakeFileSequence(std::move(files));
}

}  // namespace semslam
