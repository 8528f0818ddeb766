#pragma once
// ORB keypoints and 256-bit rotated-BRIEF descriptors as the rest of semslam sees them.

#include <array>
#include <bit>
#include <cstdint>
#include <vector>

#include "semslam/geometry/eigen_types.h"

namespace semslam {

struct Keypoint {
  Eigen::Vector2f pixel = Eigen::Vector2f::Zero();  // level-0 image coordinates, sub-pixel
  float angle_deg = 0.0f;                           // orientation (intensity centroid), [0, 360)
  float response = 0.0f;                            // FAST/Harris score used for ranking
  int level = 0;                                    // pyramid level it was detected on
};

// 256 bits, as four 64-bit words so that the Hamming distance is four popcounts.
using Descriptor = std::array<std::uint64_t, 4>;

inline int HammingDistance(const Descriptor& a, const Descriptor& b) {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
         std::popcount(a[3] ^ b[3]);
}

// The image pyramid's geometry: level l is the image scaled by 1 / scale_factor^l.
struct PyramidGeometry {
  int num_levels = 8;
  float scale_factor = 1.2f;
  std::vector<float> scale;      // scale_factor^l
  std::vector<float> inv_scale;  // 1 / scale[l]
  std::vector<float> sigma2;     // scale[l]^2: keypoint position variance at level l (pixels^2)
  std::vector<float> inv_sigma2;

  static PyramidGeometry Make(int num_levels, float scale_factor);
  // Predicted level of a point seen at `distance` when its reference observation was at `max_distance`
  // (the far limit of its scale-invariance range).
  int PredictLevel(float distance, float max_distance) const;
};

// The features of one image.
struct FeatureSet {
  std::vector<Keypoint> keypoints;
  std::vector<Descriptor> descriptors;  // one per keypoint
  PyramidGeometry pyramid;
  int image_width = 0;
  int image_height = 0;

  size_t size() const { return keypoints.size(); }
};

}  // namespace semslam
