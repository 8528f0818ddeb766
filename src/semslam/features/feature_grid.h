#pragma once
// Keypoints binned in a regular grid over the image, for "which features lie near this pixel" queries
// (projection matching, initialization, fusion).

#include <cstdint>
#include <vector>

#include "semslam/features/orb_types.h"

namespace semslam {

class FeatureGrid {
 public:
  static constexpr int kDefaultCols = 64;
  static constexpr int kDefaultRows = 48;

  FeatureGrid() = default;
  // Grid over [min_x, max_x) x [min_y, max_y) (level-0 pixels; for undistorted keypoints the bounds of the
  // undistorted image). Keypoints outside the bounds go to the nearest border cell, so none is lost.
  FeatureGrid(const FeatureSet& features, float min_x, float min_y, float max_x, float max_y,
              int cols = kDefaultCols, int rows = kDefaultRows);
  // Grid over the image the features came from.
  explicit FeatureGrid(const FeatureSet& features);

  // Indices of the keypoints with |x_k - x| <= radius and |y_k - y| <= radius (a square window, as the
  // search windows of projection matching are) whose level is in [min_level, max_level]. A negative
  // min_level means no lower bound, a negative max_level no upper bound. Indices in increasing order.
  std::vector<int> FeaturesInArea(float x, float y, float radius, int min_level = -1,
                                  int max_level = -1) const;
  // The same, appending to `out` (cleared first) to reuse its storage.
  void FeaturesInArea(float x, float y, float radius, int min_level, int max_level,
                      std::vector<int>& out) const;

  bool empty() const { return num_points_ == 0; }
  int cols() const { return cols_; }
  int rows() const { return rows_; }

 private:
  struct Entry {
    float x, y;
    std::int32_t index;
    std::int32_t level;
  };
  int cols_ = 0, rows_ = 0;
  float min_x_ = 0, min_y_ = 0;
  float inv_cell_w_ = 0, inv_cell_h_ = 0;
  int num_points_ = 0;
  std::vector<std::int32_t> cell_start_;  // cols * rows + 1 offsets into entries_
  std::vector<Entry> entries_;            // by cell, then by index
};

}  // namespace semslam
