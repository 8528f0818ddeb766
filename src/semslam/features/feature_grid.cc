#include "semslam/features/feature_grid.h"

#include <algorithm>
#include <cmath>

#include "semslam/core/error.h"

namespace semslam {

FeatureGrid::FeatureGrid(const FeatureSet& features)
    : FeatureGrid(features, 0.0f, 0.0f, static_cast<float>(std::max(features.image_width, 1)),
                  static_cast<float>(std::max(features.image_height, 1))) {}

FeatureGrid::FeatureGrid(const FeatureSet& features, float min_x, float min_y, float max_x, float max_y,
                         int cols, int rows)
    : cols_(cols), rows_(rows), min_x_(min_x), min_y_(min_y) {
  Require(cols >= 1 && rows >= 1, "FeatureGrid: need at least one cell");
  Require(std::isfinite(min_x) && std::isfinite(min_y) && std::isfinite(max_x) && std::isfinite(max_y) &&
              max_x > min_x && max_y > min_y,
          "FeatureGrid: bad bounds");
  inv_cell_w_ = static_cast<float>(cols) / (max_x - min_x);
  inv_cell_h_ = static_cast<float>(rows) / (max_y - min_y);
  num_points_ = static_cast<int>(features.keypoints.size());
  const size_t num_cells = static_cast<size_t>(cols) * static_cast<size_t>(rows);
  std::vector<std::int32_t> cell_of(features.keypoints.size());
  cell_start_.assign(num_cells + 1, 0);
  for (size_t i = 0; i < features.keypoints.size(); ++i) {
    const Keypoint& kp = features.keypoints[i];
    const int cx =
        std::clamp(static_cast<int>(std::floor((kp.pixel.x() - min_x_) * inv_cell_w_)), 0, cols - 1);
    const int cy =
        std::clamp(static_cast<int>(std::floor((kp.pixel.y() - min_y_) * inv_cell_h_)), 0, rows - 1);
    cell_of[i] = cy * cols + cx;
    ++cell_start_[static_cast<size_t>(cell_of[i]) + 1];
  }
  for (size_t c = 0; c < num_cells; ++c) cell_start_[c + 1] += cell_start_[c];
  entries_.resize(features.keypoints.size());
  std::vector<std::int32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (size_t i = 0; i < features.keypoints.size(); ++i) {
    const Keypoint& kp = features.keypoints[i];
    entries_[static_cast<size_t>(fill[static_cast<size_t>(cell_of[i])]++)] = {
        kp.pixel.x(), kp.pixel.y(), static_cast<std::int32_t>(i), static_cast<std::int32_t>(kp.level)};
  }
}

std::vector<int> FeatureGrid::FeaturesInArea(float x, float y, float radius, int min_level,
                                             int max_level) const {
  std::vector<int> out;
  FeaturesInArea(x, y, radius, min_level, max_level, out);
  return out;
}

void FeatureGrid::FeaturesInArea(float x, float y, float radius, int min_level, int max_level,
                                 std::vector<int>& out) const {
  out.clear();
  if (num_points_ == 0 || !(radius >= 0) || !std::isfinite(x) || !std::isfinite(y)) return;
  // Cells overlapping the window; border cells also hold the keypoints outside the bounds.
  const int cx0 = std::clamp(static_cast<int>(std::floor((x - radius - min_x_) * inv_cell_w_)), 0, cols_ - 1);
  const int cx1 = std::clamp(static_cast<int>(std::floor((x + radius - min_x_) * inv_cell_w_)), 0, cols_ - 1);
  const int cy0 = std::clamp(static_cast<int>(std::floor((y - radius - min_y_) * inv_cell_h_)), 0, rows_ - 1);
  const int cy1 = std::clamp(static_cast<int>(std::floor((y + radius - min_y_) * inv_cell_h_)), 0, rows_ - 1);
  const bool check_min = min_level >= 0, check_max = max_level >= 0;
  for (int cy = cy0; cy <= cy1; ++cy) {
    for (int cx = cx0; cx <= cx1; ++cx) {
      const size_t cell = static_cast<size_t>(cy * cols_ + cx);
      for (std::int32_t e = cell_start_[cell]; e < cell_start_[cell + 1]; ++e) {
        const Entry& entry = entries_[static_cast<size_t>(e)];
        if (check_min && entry.level < min_level) continue;
        if (check_max && entry.level > max_level) continue;
        if (std::abs(entry.x - x) > radius || std::abs(entry.y - y) > radius) continue;
        out.push_back(entry.index);
      }
    }
  }
  std::sort(out.begin(), out.end());
}

}  // namespace semslam
