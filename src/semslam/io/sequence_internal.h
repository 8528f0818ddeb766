#pragma once
// Shared by the sequence readers of this module (not part of its interface): a sequence is a list of image
// files with timestamps and a camera, whatever layout they came from.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "semslam/io/sequence.h"

namespace semslam::io_internal {

struct SequenceFiles {
  std::string name;
  std::filesystem::path directory;
  std::string
      camera_name;  // the camera read as the left one (ImageSequence::camera_name), empty if no choice
  std::vector<std::filesystem::path> left;
  std::vector<std::filesystem::path> right;  // empty for a monocular sequence, else one per left image
  std::vector<double> timestamps;            // one per left image
  PinholeCamera camera;                      // width and height are set from the first left image
  std::filesystem::path calibration;         // the file the camera came from (named in errors)
  std::optional<double> baseline;            // metres, for a stereo sequence
  std::optional<Trajectory> ground_truth;    // usually one pose per image (a TUM file may differ)
  std::optional<std::filesystem::path> labels;
  std::optional<std::filesystem::path> depth;
  std::optional<Eigen::Vector3d> gps_antenna_in_camera;  // metres, camera frame
};

// Reads the first left image for the image size (and checks it against a size the calibration gave, when
// camera.width/height are already set), checks the camera (CheckCameraPlausible) and the rest and builds the
// sequence.
std::unique_ptr<ImageSequence> MakeFileSequence(SequenceFiles files);

// Throws InputError naming `calibration` when the intrinsics cannot be those of a real camera at this image
// size: a field of view outside about 1..179 degrees (f = 1e-300, f = 1e9), very unequal fx and fy, or a
// principal point far outside the image (cx = 9e4 for a 1241-pixel-wide image).
void CheckCameraPlausible(const PinholeCamera& camera, const std::filesystem::path& calibration);

// "a/b/" and "a/b/." -> "a/b", made absolute.
std::filesystem::path NormalizeDirectory(const std::filesystem::path& path);

// Files of `dir` with one of the (lower-case, dotted) extensions, compared case-insensitively, in natural
// order (digit runs compare as numbers: img2 < img10).
std::vector<std::filesystem::path> ListFiles(const std::filesystem::path& dir,
                                             const std::vector<std::string>& extensions);
bool NaturalLess(const std::string& a, const std::string& b);

// The files dir/<printf(pattern, i)> for i = 0..N-1, where N is the number of files in `dir` with the
// pattern's extension; throws InputError naming the first missing one (a gap in the numbering) or when
// `dir` holds none.
std::vector<std::filesystem::path> NumberedFiles(const std::filesystem::path& dir, int digits,
                                                 const std::string& extension);

// The camera of a KITTI layout that SequenceOptions::camera names (raw: image_00..image_03; odometry:
// image_0..image_3), and the right camera of its stereo pair when it is the pair's left one (0 or 2). Throws
// InputError naming `dir` for a name the layout does not have, and naming the camera's folder when stereo is
// asked of a right camera.
struct KittiCamera {
  int index = 0;
  std::string name;                       // its folder: image_02 / image_2
  std::optional<std::string> right_name;  // image_03 / image_3 for camera 2
};
KittiCamera ChooseKittiCamera(const std::filesystem::path& dir, const SequenceOptions& options, bool raw);

}  // namespace semslam::io_internal
