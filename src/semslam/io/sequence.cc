#include "semslam/io/sequence.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <set>
#include <system_error>

#include "semslam/core/error.h"
#include "semslam/io/image_folder.h"
#include "semslam/io/kitti_odometry.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/sequence_internal.h"

namespace semslam {

namespace fs = std::filesystem;

namespace io_internal {
namespace {

class FileSequence final : public ImageSequence {
 public:
  FileSequence(SequenceFiles files, bool color) : files_(std::move(files)), color_(color) {
    if (files_.baseline) {
      stereo_ = StereoRig{files_.camera, *files_.baseline};
      stereo_->Check();
    }
  }

  std::string name() const override { return files_.name; }
  fs::path directory() const override { return files_.directory; }
  size_t size() const override { return files_.left.size(); }
  double Timestamp(size_t frame) const override {
    Require(frame < size(), fmt::format("Timestamp: frame {} out of range (sequence has {})", frame, size()));
    return files_.timestamps[frame];
  }
  const PinholeCamera& camera() const override { return files_.camera; }
  std::optional<StereoRig> stereo() const override { return stereo_; }

  cv::Mat LoadImage(size_t frame, int camera_index) const override {
    Require(frame < size(), fmt::format("LoadImage: frame {} out of range (sequence has {})", frame, size()));
    Require(camera_index == 0 || (camera_index == 1 && stereo_),
            fmt::format("LoadImage: no camera {} in sequence {}", camera_index, files_.name));
    const fs::path& file = camera_index == 0 ? files_.left[frame] : files_.right[frame];
    return CheckSize(file, ReadGreyImage(file));
  }

  std::string camera_name() const override { return files_.camera_name; }
  bool IsColor() const override { return color_; }
  cv::Mat LoadColorImage(size_t frame) const override {
    Require(frame < size(),
            fmt::format("LoadColorImage: frame {} out of range (sequence has {})", frame, size()));
    if (!color_) return {};
    const fs::path& file = files_.left[frame];
    cv::Mat image = CheckSize(file, ReadImage(file));
    if (image.channels() == 1) cv::cvtColor(image, image, cv::COLOR_GRAY2BGR);  // a grey frame in colour
    return image;
  }

  std::optional<Trajectory> GroundTruth() const override { return files_.ground_truth; }
  std::optional<fs::path> LabelDirectory() const override { return files_.labels; }
  std::optional<fs::path> DepthDirectory() const override { return files_.depth; }
  std::optional<Eigen::Vector3d> GpsAntennaInCamera() const override { return files_.gps_antenna_in_camera; }

 private:
  cv::Mat CheckSize(const fs::path& file, cv::Mat image) const {
    if (image.cols != files_.camera.width || image.rows != files_.camera.height) {
      throw InputError(file,
                       fmt::format("image is {}x{}, expected {}x{} (the size of the sequence's first image)",
                                   image.cols, image.rows, files_.camera.width, files_.camera.height));
    }
    return image;
  }

  SequenceFiles files_;
  bool color_ = false;
  std::optional<StereoRig> stereo_;
};

std::string Lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

}  // namespace

std::unique_ptr<ImageSequence> MakeFileSequence(SequenceFiles files) {
  if (files.left.empty()) throw InputError(files.directory, "the sequence has no images");
  Require(files.timestamps.size() == files.left.size(), "MakeFileSequence: one timestamp per image expected");
  Require(files.right.empty() || files.right.size() == files.left.size(),
          "MakeFileSequence: one right image per left image expected");
  Require(!files.baseline || !files.right.empty(), "MakeFileSequence: a stereo sequence needs right images");
  const cv::Mat first = ReadImage(files.left.front());
  if (files.camera.width > 0 && (files.camera.width != first.cols || files.camera.height != first.rows)) {
    throw InputError(files.left.front(),
                     fmt::format("image is {}x{} but the calibration says {}x{}", first.cols, first.rows,
                                 files.camera.width, files.camera.height));
  }
  if (files.camera.width == 0 && files.left.size() >= 3) {
    // The first image sets the size every frame must have: one of another size than the rest would make
    // every other frame "bad". Two others (the second and the last) that agree outvote it.
    const auto size_of = [](const fs::path& file) -> std::optional<cv::Size> {
      try {
        return ReadImage(file).size();
      } catch (const InputError&) {
        return std::nullopt;  // a bad frame, skipped when it is read
      }
    };
    const std::optional<cv::Size> second = size_of(files.left[1]), last = size_of(files.left.back());
    if (second && last && *second == *last && *second != first.size()) {
      throw InputError(
          files.left.front(),
          fmt::format("image is {}x{} but the sequence's others ({} and {}) are {}x{}: is it this "
                      "sequence's first image?",
                      first.cols, first.rows, files.left[1].filename().string(),
                      files.left.back().filename().string(), second->width, second->height));
    }
  }
  files.camera.width = first.cols;
  files.camera.height = first.rows;
  CheckCameraPlausible(files.camera, files.calibration.empty() ? files.directory : files.calibration);
  const bool color = first.channels() == 3;
  return std::make_unique<FileSequence>(std::move(files), color);
}

void CheckCameraPlausible(const PinholeCamera& camera, const fs::path& calibration) {
  try {
    camera.Check();
  } catch (const InvalidArgument& e) {
    throw InputError(calibration, e.what());
  }
  const double w = camera.width, h = camera.height;
  // Field of view of 1..179 degrees across the width: f between w / (2 tan 89.5 deg) and w / (2 tan 0.5 deg).
  constexpr double kMinFocalPerWidth = 0.0044, kMaxFocalPerWidth = 57.3;
  for (const auto& [name, f] : {std::pair{"fx", camera.fx}, std::pair{"fy", camera.fy}}) {
    if (f < kMinFocalPerWidth * w || f > kMaxFocalPerWidth * w) {
      throw InputError(
          SourceLocation{calibration, 0}, name,
          fmt::format("focal length {:.6g} px is not that of a camera with {}x{} images (a field of "
                      "view of 1 to 179 degrees needs {:.3g}..{:.3g} px)",
                      f, camera.width, camera.height, kMinFocalPerWidth * w, kMaxFocalPerWidth * w));
    }
  }
  if (camera.fy > 5 * camera.fx || camera.fx > 5 * camera.fy) {
    throw InputError(
        SourceLocation{calibration, 0}, "fx, fy",
        fmt::format("fx = {:.6g} and fy = {:.6g} px differ by more than a factor 5", camera.fx, camera.fy));
  }
  if (camera.cx < -0.5 * w || camera.cx > 1.5 * w || camera.cy < -0.5 * h || camera.cy > 1.5 * h) {
    throw InputError(SourceLocation{calibration, 0}, "cx, cy",
                     fmt::format("principal point ({:.6g}, {:.6g}) px lies far outside the {}x{} image",
                                 camera.cx, camera.cy, camera.width, camera.height));
  }
  if (const std::optional<Eigen::Vector2d> pixel = camera.PixelNotUndistorted()) {
    const Distortion& d = camera.distortion;
    throw InputError(
        SourceLocation{calibration, 0}, "k1, k2, p1, p2, k3",
        fmt::format(
            "the distortion ({:.6g}, {:.6g}, {:.6g}, {:.6g}, {:.6g}) does not map the {}x{} image one to "
            "one (pixel ({:.0f}, {:.0f}) cannot be undistorted): are these this camera's coefficients?",
            d.k1, d.k2, d.p1, d.p2, d.k3, camera.width, camera.height, pixel->x(), pixel->y()));
  }
}

fs::path NormalizeDirectory(const fs::path& path) {
  fs::path normal = fs::absolute(path).lexically_normal();
  if (normal.filename().empty() && normal.has_parent_path() && normal != normal.root_path()) {
    normal = normal.parent_path();
  }
  return normal;
}

bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      size_t i_end = i, j_end = j;
      while (i_end < a.size() && std::isdigit(static_cast<unsigned char>(a[i_end]))) ++i_end;
      while (j_end < b.size() && std::isdigit(static_cast<unsigned char>(b[j_end]))) ++j_end;
      // Compare the digit runs as numbers: skip leading zeros, then longer is larger, then lexicographic.
      size_t i_nz = i, j_nz = j;
      while (i_nz + 1 < i_end && a[i_nz] == '0') ++i_nz;
      while (j_nz + 1 < j_end && b[j_nz] == '0') ++j_nz;
      const std::string_view da(a.data() + i_nz, i_end - i_nz), db(b.data() + j_nz, j_end - j_nz);
      if (da.size() != db.size()) return da.size() < db.size();
      if (da != db) return da < db;
      if (i_end - i != j_end - j) return i_end - i < j_end - j;  // "01" after "1"
      i = i_end;
      j = j_end;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

std::vector<fs::path> ListFiles(const fs::path& dir, const std::vector<std::string>& extensions) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw InputError(dir, "folder not found");
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    if (!entry.is_regular_file(ec)) continue;
    const std::string ext = Lower(entry.path().extension().string());
    if (std::find(extensions.begin(), extensions.end(), ext) != extensions.end()) {
      names.push_back(entry.path().filename().string());
    }
  }
  if (ec) throw InputError(dir, fmt::format("cannot list the folder: {}", ec.message()));
  std::sort(names.begin(), names.end(), NaturalLess);
  std::vector<fs::path> files;
  files.reserve(names.size());
  for (const std::string& name : names) files.push_back(dir / name);
  return files;
}

std::vector<fs::path> NumberedFiles(const fs::path& dir, int digits, const std::string& extension) {
  const std::vector<fs::path> present = ListFiles(dir, {extension});
  if (present.empty()) throw InputError(dir, fmt::format("no {} images in the folder", extension));
  std::set<std::string> names;
  for (const fs::path& p : present) names.insert(p.filename().string());
  std::vector<fs::path> files;
  files.reserve(present.size());
  for (size_t i = 0; i < present.size(); ++i) {
    const std::string name = fmt::format("{:0{}d}{}", i, digits, extension);
    if (!names.count(name)) {
      throw InputError(dir / name,
                       fmt::format("missing: the folder holds {} {} files, which should be numbered "
                                   "{:0{}d}..{:0{}d} without gaps",
                                   present.size(), extension, 0, digits, present.size() - 1, digits));
    }
    files.push_back(dir / name);
  }
  return files;
}

KittiCamera ChooseKittiCamera(const fs::path& dir, const SequenceOptions& options, bool raw) {
  const std::string prefix = raw ? "image_0" : "image_";
  const std::string all = raw ? "image_00..image_03" : "image_0..image_3";
  const std::string layout = raw ? "KITTI raw drive" : "KITTI odometry folder";
  KittiCamera camera;
  if (!options.camera.empty()) {
    const std::string& name = options.camera;
    if (name.size() != prefix.size() + 1 || name.compare(0, prefix.size(), prefix) != 0 ||
        name.back() < '0' || name.back() > '3') {
      throw InputError(dir, fmt::format("no camera '{}' in a {}: its cameras are {}", name, layout, all));
    }
    camera.index = name.back() - '0';
  }
  const auto folder = [&](int index) { return prefix + static_cast<char>('0' + index); };
  camera.name = folder(camera.index);
  if (camera.index % 2 == 0) camera.right_name = folder(camera.index + 1);
  if (options.stereo && !camera.right_name) {
    throw InputError(
        dir / camera.name,
        fmt::format("camera {} is the right camera of the stereo pair {}/{}: stereo takes the left "
                    "one, {}",
                    camera.name, folder(camera.index - 1), camera.name, folder(camera.index - 1)));
  }
  return camera;
}

}  // namespace io_internal

namespace {

bool IsDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}
bool IsFile(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

constexpr char kExpected[] =
    "expected one of: a KITTI odometry sequence folder (image_0/, calib.txt, times.txt), a dataset root "
    "holding "
    "sequences/XX/ (KITTI odometry or the synthetic city), a KITTI raw drive folder (image_00/data/, or "
    "image_01..03, with calib_cam_to_cam.txt beside it or in its parent), or an image folder with "
    "camera.yaml (or the .yaml "
    "file "
    "itself)";

}  // namespace

std::vector<double> FrameTimestamps(const ImageSequence& sequence, size_t first, size_t end) {
  std::vector<double> times;
  times.reserve(end - first);
  for (size_t i = first; i < end; ++i) times.push_back(sequence.Timestamp(i));
  return times;
}

std::unique_ptr<ImageSequence> OpenSequence(const fs::path& path, const SequenceOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, fmt::format("not found; {}", kExpected));
  // Image folders have one camera: a camera choice is a mistake there, not something to ignore.
  const auto single_camera = [&](const fs::path& yaml) {
    if (!options.camera.empty()) {
      throw InputError(yaml,
                       fmt::format("an image folder has one camera; camera '{}' applies to KITTI "
                                   "odometry folders (image_0..image_3) and raw drives (image_00..image_03)",
                                   options.camera));
    }
    return OpenImageFolder(yaml);
  };
  if (IsFile(path)) {
    const std::string ext = path.extension().string();
    if (ext == ".yaml" || ext == ".yml") return single_camera(path);
    throw InputError(path, fmt::format("is a file, not a sequence; {}", kExpected));
  }
  if (IsDir(path / "image_0") || IsFile(path / "calib.txt")) return OpenKittiOdometry(path, options);
  for (const char* camera : {"image_00", "image_01", "image_02", "image_03"}) {
    if (IsDir(path / camera)) return OpenKittiRaw(path, options);
  }
  for (const char* name : {"camera.yaml", "camera.yml"}) {
    if (IsFile(path / name)) return single_camera(path / name);
  }
  if (IsDir(path / "sequences")) {
    std::vector<fs::path> candidates;
    for (const auto& entry : fs::directory_iterator(path / "sequences", ec)) {
      if (entry.is_directory(ec) && IsDir(entry.path() / "image_0")) candidates.push_back(entry.path());
    }
    std::sort(candidates.begin(), candidates.end());
    if (candidates.size() == 1) return OpenKittiOdometry(candidates.front(), options);
    if (candidates.empty()) {
      throw InputError(path / "sequences",
                       "holds no sequence folder with image_0/ (expected sequences/XX/image_0/)");
    }
    std::string list;
    for (const auto& c : candidates) list += (list.empty() ? "" : ", ") + c.string();
    throw InputError(path / "sequences",
                     fmt::format("holds {} sequences; pass one of them: {}", candidates.size(), list));
  }
  throw InputError(path, fmt::format("not a sequence folder; {}", kExpected));
}

}  // namespace semslam
