#include "semslam/features/image_pyramid.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"

namespace semslam {

cv::Size PyramidLevelSize(cv::Size size, float scale) {
  return {std::max(1, static_cast<int>(std::lround(static_cast<float>(size.width) / scale))),
          std::max(1, static_cast<int>(std::lround(static_cast<float>(size.height) / scale)))};
}

void InitImagePyramid(const cv::Mat& grey, const PyramidGeometry& geometry, ImagePyramid& pyramid) {
  Require(!grey.empty() && grey.type() == CV_8UC1,
          "image pyramid: need a non-empty 8-bit single-channel image");
  Require(geometry.num_levels >= 1 && static_cast<int>(geometry.scale.size()) == geometry.num_levels,
          "image pyramid: bad pyramid geometry");
  const auto n = static_cast<size_t>(geometry.num_levels);
  pyramid.levels.assign(n, cv::Mat());
  pyramid.ratio_x.assign(n, 1.0f);
  pyramid.ratio_y.assign(n, 1.0f);
  pyramid.levels[0] = grey;
}

void BuildImagePyramidLevel(const PyramidGeometry& geometry, size_t level, ImagePyramid& pyramid) {
  if (level == 0) return;
  const cv::Mat& base = pyramid.levels[0];
  const cv::Size size = PyramidLevelSize(base.size(), geometry.scale[level]);
  // Each level from the one above: the chain of small steps aliases less than one big step.
  cv::resize(pyramid.levels[level - 1], pyramid.levels[level], size, 0, 0, cv::INTER_LINEAR);
  pyramid.ratio_x[level] = static_cast<float>(base.cols) / static_cast<float>(size.width);
  pyramid.ratio_y[level] = static_cast<float>(base.rows) / static_cast<float>(size.height);
}

ImagePyramid BuildImagePyramid(const cv::Mat& grey, const PyramidGeometry& geometry) {
  ImagePyramid pyramid;
  InitImagePyramid(grey, geometry, pyramid);
  for (size_t l = 1; l < pyramid.levels.size(); ++l) BuildImagePyramidLevel(geometry, l, pyramid);
  return pyramid;
}

}  // namespace semslam
