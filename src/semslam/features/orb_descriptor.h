#pragma once
// The pieces of ORB that act on one keypoint: orientation by intensity centroid (Rosin 1999, as used by
// Rublee et al. 2011) and the rotation-steered binary test (BRIEF, Calonder et al. 2010) with semslam's own
// 256-pair sampling pattern.

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>

#include "semslam/features/orb_types.h"

namespace semslam {

// One binary test: bit = I(p1) < I(p2), points in pixels relative to the keypoint (before steering).
struct BriefPair {
  std::int8_t x1, y1, x2, y2;
  bool operator==(const BriefPair&) const = default;
};
using BriefPattern = std::array<BriefPair, 256>;

// All pattern points lie within this radius, so steered points stay within it (+0.5 rounding).
inline constexpr int kBriefPatternRadius = 13;
// Radius of the circular patch the orientation is measured on.
inline constexpr int kOrientationRadius = 15;
// Keypoints must be at least this far from their level's border for orientation and descriptor.
inline constexpr int kMinKeypointBorder = kOrientationRadius + 1;

// semslam's pattern: a table stored in the source (orb_pattern_table.inc), learned by LearnBriefPattern
// on synthetic images (see orb_pattern.h).
const BriefPattern& SemslamBriefPattern();

// Smoothing applied before the binary tests (7x7 Gaussian, sigma 2), as the tests compare single pixels.
void SmoothForDescriptor(const cv::Mat& image, cv::Mat& smoothed);

// Orientation of the patch around (x, y) in degrees, [0, 360): the direction from the keypoint to the
// intensity centroid of the disc of radius kOrientationRadius, measured in image coordinates (x right,
// y down), i.e. atan2(m01, m10). (x, y) must be >= kOrientationRadius pixels inside the image.
float IntensityCentroidAngle(const cv::Mat& image, int x, int y);

// The steered binary descriptor at (x, y) of a smoothed image, the pattern rotated by `angle_deg` (same
// convention as IntensityCentroidAngle). Bit i (word i / 64, bit i % 64) is test i of the pattern.
// (x, y) must be >= kBriefPatternRadius + 1 pixels inside the image.
Descriptor ComputeSteeredBrief(const cv::Mat& smoothed, int x, int y, float angle_deg,
                               const BriefPattern& pattern = SemslamBriefPattern());

}  // namespace semslam
