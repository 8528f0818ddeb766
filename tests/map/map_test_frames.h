#pragma once
// Frames for map tests: keypoints on a grid with random descriptors, optionally with stereo depth.

#include <cstdint>
#include <memory>
#include <random>

#include "semslam/map/map.h"
#include "support/kitti_camera.h"

namespace semslam {

// A frame with `n` keypoints on a grid, random descriptors, optional stereo depth.
inline std::shared_ptr<const FrameData> MakeData(int n, std::uint64_t seed, bool stereo) {
  std::mt19937_64 rng(seed);
  FeatureSet features;
  features.pyramid = PyramidGeometry::Make(8, 1.2f);
  features.image_width = 1241;
  features.image_height = 376;
  std::vector<float> right_u, depth;
  for (int i = 0; i < n; ++i) {
    Keypoint kp;
    kp.pixel = Eigen::Vector2f(20.0f + static_cast<float>(i % 40) * 30.0f,
                               20.0f + static_cast<float>(i / 40) * 30.0f);
    kp.angle_deg = static_cast<float>(rng() % 360);
    kp.response = static_cast<float>(rng() % 100);
    kp.level = static_cast<int>(rng() % 8);
    features.keypoints.push_back(kp);
    features.descriptors.push_back({rng(), rng(), rng(), rng()});
    if (stereo) {
      depth.push_back(i % 3 == 0 ? -1.0f : 5.0f + static_cast<float>(i % 7));
      right_u.push_back(depth.back() > 0 ? kp.pixel.x() - 20.0f : -1.0f);
    }
  }
  std::optional<StereoRig> rig;
  if (stereo) rig = StereoRig{KittiCamera(), 0.54};
  return MakeFrameData(KittiCamera(), rig, std::move(features), std::move(right_u), std::move(depth));
}

inline Frame MakeFrame(std::uint64_t id, int n, bool stereo, const Eigen::Vector3d& center) {
  Frame frame(id, 0.1 * static_cast<double>(id), MakeData(n, id + 7, stereo));
  frame.SetPose(Rigid3d(Eigen::Quaterniond::Identity(), -center));
  return frame;
}

}  // namespace semslam
