#pragma once
// Images shared by the feature tests: real KITTI frames when ../shared/data is there, and synthetic ones.

#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "semslam/features/orb_pattern.h"

namespace semslam::testing {

// A KITTI-sized (1241x376) grey image of random shapes and textures (no data needed).
inline cv::Mat SyntheticStreetSizedImage(std::uint64_t seed = 7) {
  return MakeSyntheticTrainingImage(seed, cv::Size(1241, 376));
}

// KITTI 07 left frame `index` (0..159) under `root` (the kitti_odom_07_3dv folder).
inline cv::Mat Kitti07Frame(const std::filesystem::path& root, int index) {
  char name[32];
  std::snprintf(name, sizeof(name), "%06d.png", index);
  return cv::imread((root / "sequences" / "07" / "image_0" / name).string(), cv::IMREAD_GRAYSCALE);
}

}  // namespace semslam::testing
