#include "semslam/features/orb_types.h"

#include <algorithm>
#include <cmath>

namespace semslam {

PyramidGeometry PyramidGeometry::Make(int num_levels, float scale_factor) {
  PyramidGeometry g;
  g.num_levels = num_levels;
  g.scale_factor = scale_factor;
  for (int l = 0; l < num_levels; ++l) {
    const float s = std::pow(scale_factor, static_cast<float>(l));
    g.scale.push_back(s);
    g.inv_scale.push_back(1.0f / s);
    g.sigma2.push_back(s * s);
    g.inv_sigma2.push_back(1.0f / (s * s));
  }
  return g;
}

int PyramidGeometry::PredictLevel(float distance, float max_distance) const {
  if (distance <= 0) return 0;
  const float ratio = max_distance / distance;
  const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(scale_factor)));
  return std::clamp(level, 0, num_levels - 1);
}

}  // namespace semslam
