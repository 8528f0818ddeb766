#pragma once
// An image sequence from any source (KITTI odometry, KITTI raw, an image folder, the synthetic city).

#include <filesystem>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <vector>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/trajectory.h"

namespace semslam {

// Which camera of a recording to read.
struct SequenceOptions {
  // The camera read as the left one. Empty: the default, image_00 of a KITTI raw drive or image_0 of a KITTI
  // odometry folder. KITTI raw drives have image_00..image_03, KITTI odometry folders image_0..image_3; the
  // stereo pairs are 00/01 and 02/03 (0/1 and 2/3), so choosing 00 or 02 gives the pair's right camera as
  // camera 1, and 01 or 03 is a monocular camera. Other sequences have one camera: a name is an error there.
  std::string camera;
  // The chosen camera must be the left one of a stereo pair whose right images are there (an InputError
  // naming the missing folder otherwise). Without it a sequence is stereo when it can be.
  bool stereo = false;
};

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
  // The camera read as camera 0 (SequenceOptions::camera; "image_00", "image_2", ...), empty when the
  // sequence has no choice of camera.
  virtual std::string camera_name() const { return {}; }
  // Whether camera 0 records colour (its first image has three or four channels).
  virtual bool IsColor() const { return false; }
  // Camera 0's image in colour, 8-bit BGR, for a colour camera; an empty Mat for a grey one. LoadImage(frame,
  // 0) is GreyFromColor of this image: a caller that needs both converts it rather than reading it twice.
  virtual cv::Mat LoadColorImage(size_t /*frame*/) const { return {}; }
  // Ground-truth trajectory (camera 0, world = first camera), when the sequence has one.
  virtual std::optional<Trajectory> GroundTruth() const { return std::nullopt; }
  // Folder of per-frame label images (Cityscapes trainIds), when the sequence has one (the synthetic city).
  virtual std::optional<std::filesystem::path> LabelDirectory() const { return std::nullopt; }
  // Folder of per-frame depth images (uint16, metres * 256), when the sequence has one.
  virtual std::optional<std::filesystem::path> DepthDirectory() const { return std::nullopt; }
  // Where its GPS log's positions were measured, in camera 0's frame (metres), when its calibration says: a
  // KITTI raw drive's OXTS unit (calib_imu_to_velo.txt, calib_velo_to_cam.txt).
  virtual std::optional<Eigen::Vector3d> GpsAntennaInCamera() const { return std::nullopt; }
};

// Opens whatever `path` holds: a KITTI odometry sequence (image_0/ + calib.txt), a KITTI raw drive
// (image_00/data + calibration files), a synthetic city output folder (sequences/00 inside it), or an image
// folder with camera.yaml. Throws InputError explaining what was expected when none matches.
// `options` chooses the camera of a KITTI folder (InputError naming the folder for a camera it does not
// have).
std::unique_ptr<ImageSequence> OpenSequence(const std::filesystem::path& path,
                                            const SequenceOptions& options = {});
// The timestamps of frames [first, end) of a sequence, in order.
std::vector<double> FrameTimestamps(const ImageSequence& sequence, size_t first, size_t end);

// Reads an image as 8 bits (16-bit images are scaled), grey or BGR (an alpha channel is dropped). Throws
// InputError naming the file if it is missing or cannot be decoded.
cv::Mat ReadImage(const std::filesystem::path& path);
// The same checks, but the pixels as stored (16-bit depth stays 16 bit, channels as they are): for label and
// depth images.
cv::Mat ReadImageUnchanged(const std::filesystem::path& path);
// Reads an 8-bit grey image, converting colour to grey.
cv::Mat ReadGreyImage(const std::filesystem::path& path);
// An 8-bit BGR image in grey (OpenCV's BGR2GRAY weights); an 8-bit grey image as it is.
cv::Mat GreyFromColor(const cv::Mat& image);
// Writes a PNG atomically (PNG compression level 1 unless given).
void WritePng(const std::filesystem::path& path, const cv::Mat& image, int compression = 1);

}  // namespace semslam
