#pragma once
// The scale pyramid ORB features are detected on, shared by the extractor and the stereo matcher.
//
// Level l is the image resized (bilinear, pixel centres aligned as cv::resize does) to
// round(width / s^l) x round(height / s^l). Because of the rounding, the true ratio between level 0 and
// level l differs slightly from s^l; the pyramid keeps the true ratios per axis so that level pixels map
// to level-0 pixels exactly:  x0 = (xl + 0.5) * ratio_x[l] - 0.5.

#include <opencv2/core.hpp>
#include <vector>

#include "semslam/features/orb_types.h"

namespace semslam {

struct ImagePyramid {
  std::vector<cv::Mat> levels;  // levels[0] shares the input image's pixels (no copy)
  std::vector<float> ratio_x;   // level-0 pixels per level-l pixel, horizontally
  std::vector<float> ratio_y;   // and vertically

  int num_levels() const { return static_cast<int>(levels.size()); }
  bool empty() const { return levels.empty(); }

  float ToLevel0X(float x, int level) const {
    return (x + 0.5f) * ratio_x[static_cast<size_t>(level)] - 0.5f;
  }
  float ToLevel0Y(float y, int level) const {
    return (y + 0.5f) * ratio_y[static_cast<size_t>(level)] - 0.5f;
  }
  float FromLevel0X(float x0, int level) const {
    return (x0 + 0.5f) / ratio_x[static_cast<size_t>(level)] - 0.5f;
  }
  float FromLevel0Y(float y0, int level) const {
    return (y0 + 0.5f) / ratio_y[static_cast<size_t>(level)] - 0.5f;
  }
};

// Builds the pyramid of an 8-bit single-channel image with the given geometry. Throws InvalidArgument on
// an empty or non-CV_8UC1 image.
ImagePyramid BuildImagePyramid(const cv::Mat& grey, const PyramidGeometry& geometry);

// Step by step: InitImagePyramid sets level 0 and sizes the vectors; BuildImagePyramidLevel(l) makes level l
// from level l - 1 (so levels can be processed while later ones are being built).
void InitImagePyramid(const cv::Mat& grey, const PyramidGeometry& geometry, ImagePyramid& pyramid);
void BuildImagePyramidLevel(const PyramidGeometry& geometry, size_t level, ImagePyramid& pyramid);

// Size of level `level` for a level-0 image of `size`.
cv::Size PyramidLevelSize(cv::Size size, float scale);

}  // namespace semslam
