#include "semslam/io/kitti_odometry.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/text_reader.h"
#include "semslam/io/sequence_internal.h"
#include "semslam/io/trajectory_io.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

Eigen::Matrix3x4d ParseMatrix3x4(const std::vector<std::string_view>& tokens, const SourceLocation& where,
                                 const std::string& key) {
  if (tokens.size() != 12) {
    throw InputError(where, key,
                     fmt::format("expected 12 numbers (a row-major 3x4 matrix), found {}", tokens.size()));
  }
  Eigen::Matrix3x4d m;
  for (int i = 0; i < 12; ++i) m(i / 4, i % 4) = ParseDouble(tokens[i], where, fmt::format("{}[{}]", key, i));
  return m;
}

// A rectified projection matrix K [I | t]: positive focal lengths, no skew, last row (0 0 1 *).
void CheckProjection(const Eigen::Matrix3x4d& p, const SourceLocation& where, const std::string& key) {
  if (!(p(0, 0) > 0) || !(p(1, 1) > 0)) {
    throw InputError(where, key,
                     fmt::format("focal lengths must be positive (found {} and {})", p(0, 0), p(1, 1)));
  }
  if (p(2, 0) != 0 || p(2, 1) != 0 || std::abs(p(2, 2) - 1.0) > 1e-9) {
    throw InputError(where, key, "the third row must start with 0 0 1 (a rectified projection K [I|t])");
  }
}

std::string FormatRow(const std::string& key, const Eigen::Matrix3x4d& m) {
  std::string line = key + ":";
  for (int i = 0; i < 12; ++i) line += fmt::format(" {:.12e}", m(i / 4, i % 4));
  line += '\n';
  return line;
}

}  // namespace

PinholeCamera KittiCalibration::Camera0(int width, int height) const {
  Require(num_projections >= 1, "KittiCalibration::Camera0: no P0");
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = projection[0](0, 0);
  camera.fy = projection[0](1, 1);
  camera.cx = projection[0](0, 2);
  camera.cy = projection[0](1, 2);
  camera.Check();
  return camera;
}

std::optional<StereoRig> KittiCalibration::Stereo01(int width, int height) const {
  if (num_projections < 2) return std::nullopt;
  StereoRig rig;
  rig.left = Camera0(width, height);
  rig.baseline = -projection[1](0, 3) / projection[1](0, 0);
  rig.Check();
  return rig;
}

KittiCalibration ReadKittiCalibration(const fs::path& path) {
  TextReader reader(path);
  KittiCalibration calibration;
  std::array<bool, 4> seen{};
  std::array<SourceLocation, 4> seen_at{};
  while (const auto line = reader.NextLine()) {
    const std::string_view text = Trim(*line);
    if (text.empty() || text.front() == '#') continue;
    const SourceLocation where = reader.Where();
    const size_t colon = text.find(':');
    if (colon == std::string_view::npos) {
      throw InputError(where, "expected 'KEY: numbers' (P0: followed by 12 numbers, ...)");
    }
    const std::string key(Trim(text.substr(0, colon)));
    const auto tokens = SplitTokens(text.substr(colon + 1));
    if (key.size() == 2 && key[0] == 'P' && key[1] >= '0' && key[1] <= '3') {
      const int index = key[1] - '0';
      if (seen[index]) throw InputError(where, key, "given twice");
      calibration.projection[index] = ParseMatrix3x4(tokens, where, key);
      CheckProjection(calibration.projection[index], where, key);
      seen[index] = true;
      seen_at[index] = where;
    } else if (key == "Tr") {
      if (calibration.velo_to_cam) throw InputError(where, key, "given twice");
      calibration.velo_to_cam = ParseMatrix3x4(tokens, where, key);
    }
    // Other keys (R0_rect, Tr_imu_to_velo, ... of other KITTI benchmarks) are not used here.
  }
  if (!seen[0])
    throw InputError(SourceLocation{path, 0}, "P0",
                     "missing (calib.txt needs at least the row 'P0: 12 numbers')");
  while (calibration.num_projections < 4 && seen[calibration.num_projections]) ++calibration.num_projections;
  for (int i = calibration.num_projections; i < 4; ++i) {
    if (seen[i]) {
      throw InputError(
          seen_at[i], fmt::format("P{}", i),
          fmt::format("given without P{} (rows must be P0, P1, ... in order)", calibration.num_projections));
    }
  }
  if (calibration.num_projections >= 2) {
    const Eigen::Matrix3x4d& p0 = calibration.projection[0];
    const Eigen::Matrix3x4d& p1 = calibration.projection[1];
    if ((p1.leftCols<3>() - p0.leftCols<3>()).cwiseAbs().maxCoeff() > 1e-6 * p0(0, 0)) {
      throw InputError(seen_at[1], "P1", "intrinsics differ from P0's: not a rectified stereo pair");
    }
    if (!(-p1(0, 3) / p1(0, 0) > 0)) {
      throw InputError(
          seen_at[1], "P1[3]",
          fmt::format("gives baseline {} m; the right camera must lie on the left camera's +x axis "
                      "(P1[3] = -fx * baseline < 0)",
                      -p1(0, 3) / p1(0, 0)));
    }
  }
  return calibration;
}

void WriteKittiCalibration(const fs::path& path, const KittiCalibration& calibration) {
  Require(calibration.num_projections >= 1 && calibration.num_projections <= 4,
          "WriteKittiCalibration: num_projections must be in 1..4");
  std::string text;
  for (int i = 0; i < calibration.num_projections; ++i) {
    text += FormatRow(fmt::format("P{}", i), calibration.projection[i]);
  }
  if (calibration.velo_to_cam) text += FormatRow("Tr", *calibration.velo_to_cam);
  WriteFileAtomically(path, text);
}

KittiCalibration MakeKittiCalibration(const StereoRig& rig) {
  rig.Check();
  Eigen::Matrix3x4d p0 = Eigen::Matrix3x4d::Zero();
  p0.leftCols<3>() = rig.left.K();
  Eigen::Matrix3x4d p1 = p0;
  p1(0, 3) = -rig.left.fx * rig.baseline;
  KittiCalibration calibration;
  calibration.projection = {p0, p1, p0, p1};
  calibration.num_projections = 4;
  return calibration;
}

std::unique_ptr<ImageSequence> OpenKittiOdometry(const fs::path& sequence_dir) {
  io_internal::SequenceFiles files;
  files.directory = io_internal::NormalizeDirectory(sequence_dir);
  const fs::path& dir = files.directory;
  files.name = dir.filename().string();
  std::error_code ec;
  if (!fs::is_directory(dir / "image_0", ec)) {
    throw InputError(dir / "image_0", "folder not found (a KITTI odometry sequence has image_0/%06d.png)");
  }
  files.left = io_internal::NumberedFiles(dir / "image_0", 6, ".png");
  const size_t n = files.left.size();

  const KittiCalibration calibration = ReadKittiCalibration(dir / "calib.txt");
  files.camera = calibration.Camera0(1, 1);
  files.camera.width = files.camera.height = 0;  // set from the first image
  files.calibration = dir / "calib.txt";

  const fs::path times_file = dir / "times.txt";
  const std::vector<double> times = ReadTimes(times_file);
  if (times.size() < n) {
    throw InputError(times_file, fmt::format("lists {} timestamps, fewer than the {} images in image_0/",
                                             times.size(), n));
  }
  files.timestamps.assign(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(n));

  if (fs::is_directory(dir / "image_1", ec) && calibration.num_projections >= 2) {
    const std::vector<fs::path> right = io_internal::ListFiles(dir / "image_1", {".png"});
    if (right.size() < n) {
      throw InputError(dir / "image_1",
                       fmt::format("holds {} images, fewer than the {} in image_0/ (stereo pairs "
                                   "need both)",
                                   right.size(), n));
    }
    for (size_t i = 0; i < n; ++i) files.right.push_back(dir / "image_1" / files.left[i].filename());
    files.baseline = -calibration.projection[1](0, 3) / calibration.projection[1](0, 0);
  }

  const fs::path poses = dir.parent_path().parent_path() / "poses" / (files.name + ".txt");
  if (fs::is_regular_file(poses, ec)) {
    const std::vector<Rigid3d> world_from_camera = ReadKittiPoses(poses);
    if (world_from_camera.size() < n) {
      throw InputError(poses, fmt::format("holds {} poses, fewer than the {} images of the sequence",
                                          world_from_camera.size(), n));
    }
    Trajectory truth;
    truth.reserve(n);
    for (size_t i = 0; i < n; ++i) truth.push_back({files.timestamps[i], world_from_camera[i]});
    files.ground_truth = std::move(truth);
  }
  if (fs::is_directory(dir / "label_0", ec)) files.labels = dir / "label_0";
  if (fs::is_directory(dir / "depth_0", ec)) files.depth = dir / "depth_0";
  return io_internal::MakeFileSequence(std::move(files));
}

}  // namespace semslam
