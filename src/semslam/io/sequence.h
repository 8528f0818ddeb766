#pragma once
// An image sequence from any source (KITTI odometry, KITTI raw, an image folder, the synthetic city).

#include <filesystem>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/trajectory.h"

namespace semslam {

class ImageSequence {
 public:
  virtual ~ImageSequence() = default;

  virtual std::string name() const = 0;
  virtual std::filesystem::path directory() const = 0;
  // Number of frames that have a (left) image.
  virtual size_t size() const = 0;
  virtual double Timestamp(size_t frame) const = 0;
  virtual const PinholeCamera& camera() const = 0;
  // The rectified stereo rig, when the sequence has a second camera.
  virtual std::optional<StereoRig> stereo() const = 0;
  // 8-bit grey image of camera 0 (left) or 1 (right). Throws InputError naming the file when it is
  // missing, corrupt, or not of the calibrated size.
  virtual cv::Mat LoadImage(size_t frame, int camera_index = 0) const = 0;
  // Ground-truth trajectory (camera 0, world = first camera), when the sequence has one.
  virtual std::optional<Trajectory> GroundTruth() const { return std::nullopt; }
  // Folder of per-frame label images (Cityscapes trainIds), when the sequence has one (the synthetic city).
  virtual std::optional<std::filesystem::path> LabelDirectory() const { return std::nullopt; }
  // Folder of per-frame depth images (uint16, metres * 256), when the sequence has one.
  virtual std::optional<std::filesystem::path> DepthDirectory() const { return std::nullopt; }
};

// Opens whatever `path` holds: a KITTI odometry sequence (image_0/ + calib.txt), a KITTI raw drive
// (image_00/data + calibration files), a synthetic city output folder (sequences/00 inside it), or an image
// folder with camera.yaml. Throws InputError explaining what was expected when none matches.
std::unique_ptr<ImageSequence> OpenSequence(const std::filesystem::path& path);

// Reads an 8-bit grey image, converting colour to grey. Throws InputError naming the file if it is missing or
// cannot be decoded.
cv::Mat ReadGreyImage(const std::filesystem::path& path);
// Writes a PNG atomically (PNG compression level 1 unless given).
void WritePng(const std::filesystem::path& path, const cv::Mat& image, int compression = 1);

}  // namespace semslam
