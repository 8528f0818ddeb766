#include "semslam/features/image_pyramid.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "semslam/core/error.h"

namespace semslam {

cv::Size PyramidLevelSize(cv::Size size, float scale) {
  return {std::max(1, static_cast<int>(std::lround(static_cast<float>(size.width) / scale))),
          std::max(1, static_cast<int>(std::lround(static_cast<float>(size.height) / scale)))};
}

ImagePyramid BuildImagePyramid(const cv::Mat& grey, const PyramidGeometry& geometry) {
  Require(!grey.empty() && grey.type() == CV_8UC1, "image pyramid: need a non-empty 8-bit single-channel image");
  Require(geometry.num_levels >= 1 && static_cast<int>(geometry.scale.size()) == geometry.num_levels,
          "image pyramid: bad pyramid geometry");
  ImagePyramid pyramid;
  const auto n = static_cast<size_t>(geometry.num_levels);
  pyramid.levels.resize(n);
  pyramid.ratio_x.resize(n);
  pyramid.ratio_y.resize(n);
  pyramid.levels[0] = grey;
  pyramid.ratio_x[0] = pyramid.ratio_y[0] = 1.0f;
  for (size_t l = 1; l < n; ++l) {
    const cv::Size size = PyramidLevelSize(grey.size(), geometry.scale[l]);
    // Each level from the one above: the chain of small steps aliases less than one big step.
    cv::resize(pyramid.levels[l - 1], pyramid.levels[l], size, 0, 0, cv::INTER_LINEAR);
    pyramid.ratio_x[l] = static_cast<float>(grey.cols) / static_cast<float>(size.width);
    pyramid.ratio_y[l] = static_cast<float>(grey.rows) / static_cast<float>(size.height);
  }
  return pyramid;
}

}  // namespace semslam
