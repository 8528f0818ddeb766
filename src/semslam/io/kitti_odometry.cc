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

PinholeCamera KittiCalibration::Camera(int index, int width, int height) const {
  Require(index >= 0 && index < num_projections,
          fmt::format("KittiCalibration::Camera: no P{} (the calibration has {})", index, num_projections));
  const Eigen::Matrix3x4d& p = projection[static_cast<size_t>(index)];
  PinholeCamera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = p(0, 0);
  camera.fy = p(1, 1);
  camera.cx = p(0, 2);
  camera.cy = p(1, 2);
  camera.Check();
  return camera;
}

Eigen::Vector3d KittiCalibration::Offset(int index) const {
  Require(index >= 0 && index < num_projections,
          fmt::format("KittiCalibration::Offset: no P{} (the calibration has {})", index, num_projections));
  return ProjectionOffset(projection[static_cast<size_t>(index)]);
}

Eigen::Vector3d ProjectionOffset(const Eigen::Matrix3x4d& p) {
  // P(:,3) = K t with K upper triangular: back-substitute.
  const double tz = p(2, 3);
  const double ty = (p(1, 3) - p(1, 2) * tz) / p(1, 1);
  const double tx = (p(0, 3) - p(0, 1) * ty - p(0, 2) * tz) / p(0, 0);
  return {tx, ty, tz};
}

std::optional<StereoRig> KittiCalibration::Stereo(int left, int width, int height) const {
  Require(left == 0 || left == 2, "KittiCalibration::Stereo: the left camera of a pair is 0 or 2");
  if (num_projections < left + 2) return std::nullopt;
  StereoRig rig;
  rig.left = Camera(left, width, height);
  rig.baseline = Offset(left).x() - Offset(left + 1).x();
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
  // The pairs 0/1 and 2/3 are rectified stereo rigs: shared intrinsics, the right camera on the left one's
  // +x.
  for (const int left : {0, 2}) {
    if (calibration.num_projections < left + 2) continue;
    const Eigen::Matrix3x4d& pl = calibration.projection[static_cast<size_t>(left)];
    const Eigen::Matrix3x4d& pr = calibration.projection[static_cast<size_t>(left + 1)];
    const SourceLocation& where = seen_at[static_cast<size_t>(left + 1)];
    if ((pr.leftCols<3>() - pl.leftCols<3>()).cwiseAbs().maxCoeff() > 1e-6 * pl(0, 0)) {
      throw InputError(where, fmt::format("P{}", left + 1),
                       fmt::format("intrinsics differ from P{}'s: not a rectified stereo pair", left));
    }
    const double baseline = calibration.Offset(left).x() - calibration.Offset(left + 1).x();
    if (!(baseline > 0)) {
      throw InputError(where, fmt::format("P{}[3]", left + 1),
                       fmt::format("gives baseline {} m; the right camera must lie on the left camera's +x "
                                   "axis (P{}[3] < P{}[3])",
                                   baseline, left + 1, left));
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

std::unique_ptr<ImageSequence> OpenKittiOdometry(const fs::path& sequence_dir,
                                                 const SequenceOptions& options) {
  io_internal::SequenceFiles files;
  files.directory = io_internal::NormalizeDirectory(sequence_dir);
  const fs::path& dir = files.directory;
  files.name = dir.filename().string();
  const io_internal::KittiCamera chosen = io_internal::ChooseKittiCamera(dir, options, /*raw=*/false);
  files.camera_name = chosen.name;
  std::error_code ec;
  if (!fs::is_directory(dir / chosen.name, ec)) {
    throw InputError(dir / chosen.name, fmt::format("folder not found (a KITTI odometry sequence has "
                                                    "{}/%06d.png for camera {})",
                                                    chosen.name, chosen.name));
  }
  files.left = io_internal::NumberedFiles(dir / chosen.name, 6, ".png");
  const size_t n = files.left.size();

  const KittiCalibration calibration = ReadKittiCalibration(dir / "calib.txt");
  if (chosen.index >= calibration.num_projections) {
    throw InputError(SourceLocation{dir / "calib.txt", 0}, fmt::format("P{}", chosen.index),
                     fmt::format("missing: camera {} needs it", chosen.name));
  }
  files.camera = calibration.Camera(chosen.index, 1, 1);
  files.camera.width = files.camera.height = 0;  // set from the first image
  files.calibration = dir / "calib.txt";

  const fs::path times_file = dir / "times.txt";
  const std::vector<double> times = ReadTimes(times_file);
  if (times.size() < n) {
    throw InputError(times_file, fmt::format("lists {} timestamps, fewer than the {} images in {}/",
                                             times.size(), n, chosen.name));
  }
  files.timestamps.assign(times.begin(), times.begin() + static_cast<std::ptrdiff_t>(n));

  if (chosen.right_name) {
    const std::string& right_name = *chosen.right_name;
    const bool has_folder = fs::is_directory(dir / right_name, ec);
    const bool has_row = calibration.num_projections >= chosen.index + 2;
    if (options.stereo && !has_folder) {
      throw InputError(dir / right_name, fmt::format("folder not found: stereo with camera {} needs {}",
                                                     chosen.name, right_name));
    }
    if (options.stereo && !has_row) {
      throw InputError(
          SourceLocation{dir / "calib.txt", 0}, fmt::format("P{}", chosen.index + 1),
          fmt::format("missing: stereo with camera {} needs the row of {}", chosen.name, right_name));
    }
    if (has_folder && has_row) {
      const std::vector<fs::path> right = io_internal::ListFiles(dir / right_name, {".png"});
      if (right.size() < n) {
        throw InputError(dir / right_name,
                         fmt::format("holds {} images, fewer than the {} in {}/ (stereo pairs need both)",
                                     right.size(), n, chosen.name));
      }
      for (size_t i = 0; i < n; ++i) files.right.push_back(dir / right_name / files.left[i].filename());
      files.baseline = calibration.Offset(chosen.index).x() - calibration.Offset(chosen.index + 1).x();
    }
  }

  const fs::path poses = dir.parent_path().parent_path() / "poses" / (files.name + ".txt");
  if (fs::is_regular_file(poses, ec)) {
    const std::vector<Rigid3d> world_from_camera0 = ReadKittiPoses(poses);
    if (world_from_camera0.size() < n) {
      throw InputError(poses, fmt::format("holds {} poses, fewer than the {} images of the sequence",
                                          world_from_camera0.size(), n));
    }
    // The poses are camera 0's in the first camera 0's frame; the chosen camera's, in its own first frame,
    // are camera_from_camera0 * pose * camera0_from_camera (a translation: the rectified cameras are
    // parallel).
    const Rigid3d camera_from_camera0(Eigen::Quaterniond::Identity(), calibration.Offset(chosen.index));
    const Rigid3d camera0_from_camera = camera_from_camera0.Inverse();
    Trajectory truth;
    truth.reserve(n);
    for (size_t i = 0; i < n; ++i) {
      truth.push_back(
          {files.timestamps[i], camera_from_camera0 * world_from_camera0[i] * camera0_from_camera});
    }
    files.ground_truth = std::move(truth);
  }
  // The synthetic city's labels and depth are camera 0's.
  if (chosen.index == 0 && fs::is_directory(dir / "label_0", ec)) files.labels = dir / "label_0";
  if (chosen.index == 0 && fs::is_directory(dir / "depth_0", ec)) files.depth = dir / "depth_0";
  return io_internal::MakeFileSequence(std::move(files));
}

}  // namespace semslam
