#pragma once
// A folder of images with a YAML camera file (camera.yaml). See docs/formats.md for the keys:
//
//   fx: 718.856          # required: pinhole intrinsics in pixels
//   fy: 718.856
//   cx: 607.1928
//   cy: 185.2157
//   width: 1241          # optional; when given, the first image must have this size
//   height: 376
//   k1: 0.0              # optional radial-tangential distortion (OpenCV order k1 k2 p1 p2 k3)
//   baseline: 0.537      # optional, metres: a rectified stereo pair, with right_images
//   right_images: right  # folder of right images (the same count, paired in sorted order)
//   images: left         # optional folder of the left images (default: the folder of camera.yaml)
//   fps: 10              # optional frame rate; or
//   times: times.txt     # optional file with one timestamp per line (may list more than there are images)
//   ground_truth: gt.txt # optional trajectory (TUM, or KITTI with one pose per image)
//   labels: labels       # optional folders of per-frame label / depth images
//   depth: depth
//   name: my_drive       # optional (default: the images folder's name)
//
// Relative paths are relative to the folder holding camera.yaml. Images are .png/.jpg/.jpeg files, in natural
// file-name order (img2 before img10). Without fps and times, frames are 0.1 s apart (10 Hz).

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "semslam/geometry/camera.h"
#include "semslam/io/sequence.h"

namespace semslam {

struct CameraYaml {
  std::filesystem::path file;
  PinholeCamera camera;  // width and height stay 0 when the file does not give them
  std::optional<double> baseline;
  std::optional<double> fps;
  std::filesystem::path images;  // absolute: the folder of the left images
  std::optional<std::filesystem::path> right_images, times, ground_truth, labels, depth;
  std::optional<std::string> name;
};

// Parses a camera file. Throws InputError naming the file, line and key for malformed YAML, unknown keys,
// missing required keys and bad values.
CameraYaml ReadCameraYaml(const std::filesystem::path& path);
// Writes one (paths relative to its folder when they lie inside it).
void WriteCameraYaml(const std::filesystem::path& path, const CameraYaml& camera_yaml);

// Opens an image folder given either the folder holding camera.yaml (or camera.yml) or the YAML file itself.
std::unique_ptr<ImageSequence> OpenImageFolder(const std::filesystem::path& folder_or_yaml);

}  // namespace semslam
