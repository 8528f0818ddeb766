#pragma once
// Pinhole camera with optional radial-tangential (Brown-Conrady, OpenCV order) distortion, and the
// rectified stereo rig built on it. Camera frame: x right, y down, z forward (optical axis).

#include <optional>
#include <string>

#include "semslam/geometry/eigen_types.h"

namespace semslam {

struct Distortion {
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  bool IsZero() const { return k1 == 0 && k2 == 0 && p1 == 0 && p2 == 0 && k3 == 0; }
};

struct PinholeCamera {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Distortion distortion;

  // Throws InvalidArgument naming the bad parameter.
  void Check() const;

  Eigen::Matrix3d K() const;
  // Pixel of a point in the camera frame. The caller checks depth > 0.
  Eigen::Vector2d Project(const Eigen::Vector3d& point_in_camera) const;
  // Projects only points in front of the camera and inside the image (with `margin` pixels).
  std::optional<Eigen::Vector2d> ProjectIfVisible(const Eigen::Vector3d& point_in_camera, double margin = 0.0) const;
  // Normalized image coordinates (x/z, y/z) of a pixel, with distortion removed.
  Eigen::Vector2d PixelToNormalized(const Eigen::Vector2d& pixel) const;
  // Bearing (unit length) of a pixel.
  Eigen::Vector3d Unproject(const Eigen::Vector2d& pixel) const;
  // A pixel on the image's border that the distortion does not map one to one (PixelToNormalized then
  // Project misses it by more than 0.1 px, or it undistorts out of order with its neighbours along the
  // border); nullopt when the model is usable over the whole image.
  std::optional<Eigen::Vector2d> PixelNotUndistorted() const;
  // The point at `depth` along the pixel's ray (depth = z in the camera frame).
  Eigen::Vector3d UnprojectDepth(const Eigen::Vector2d& pixel, double depth) const {
    const Eigen::Vector2d n = PixelToNormalized(pixel);
    return Eigen::Vector3d(n.x() * depth, n.y() * depth, depth);
  }
  bool InImage(const Eigen::Vector2d& pixel, double margin = 0.0) const {
    return pixel.x() >= margin && pixel.y() >= margin && pixel.x() <= width - 1 - margin &&
           pixel.y() <= height - 1 - margin;
  }
  // The same camera for an image scaled by `factor` (pyramid levels, downsampled segmentation).
  PinholeCamera Scaled(double factor) const;

  std::string ToString() const;
};

// A rectified stereo pair: the right camera sits `baseline` metres along the left camera's +x axis and
// shares its intrinsics, so a point at depth z appears `fx * baseline / z` pixels further left.
struct StereoRig {
  PinholeCamera left;
  double baseline = 0.0;

  void Check() const;
  double FocalBaseline() const { return left.fx * baseline; }
  double DepthFromDisparity(double disparity) const { return FocalBaseline() / disparity; }
  double DisparityFromDepth(double depth) const { return FocalBaseline() / depth; }
  // u coordinate in the right image of a point in the left camera frame.
  double ProjectRightU(const Eigen::Vector3d& point_in_left) const {
    return left.fx * (point_in_left.x() - baseline) / point_in_left.z() + left.cx;
  }
  // Left-camera point from a left pixel and its disparity (u_left - u_right).
  Eigen::Vector3d Triangulate(const Eigen::Vector2d& left_pixel, double disparity) const {
    return left.UnprojectDepth(left_pixel, DepthFromDisparity(disparity));
  }
};

}  // namespace semslam
