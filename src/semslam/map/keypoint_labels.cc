#include "semslam/map/keypoint_labels.h"

#include <algorithm>
#include <cmath>

#include "semslam/core/error.h"
#include "semslam/semantics/label_fusion.h"

namespace semslam {

void KeypointLabels::Assign(const std::vector<float>& rows) {
  Require(rows.size() % kNumClasses == 0, "keypoint labels: rows must hold 19 values per keypoint");
  const size_t n = rows.size() / kNumClasses;
  quantized_.assign(rows.size(), 0);
  labeled_.assign(n, 0);
  for (size_t k = 0; k < n; ++k) {
    const float* row = rows.data() + k * kNumClasses;
    if (!IsSampledObservation(row)) continue;
    labeled_[k] = 1;
    for (int c = 0; c < kNumClasses; ++c) {
      const float steps = std::round(-row[c] / kStep);
      quantized_[k * kNumClasses + static_cast<size_t>(c)] =
          static_cast<std::uint8_t>(std::clamp(steps, 0.0f, 255.0f));
    }
  }
}

bool KeypointLabels::Get(size_t keypoint, ClassLogProbs* log_probs) const {
  if (!Has(keypoint)) return false;
  const std::uint8_t* q = quantized_.data() + keypoint * kNumClasses;
  for (int c = 0; c < kNumClasses; ++c)
    (*log_probs)[static_cast<size_t>(c)] = -kStep * static_cast<float>(q[c]);
  return true;
}

void KeypointLabels::Restore(std::vector<std::uint8_t> quantized, std::vector<std::uint8_t> labeled) {
  Require(quantized.size() == labeled.size() * kNumClasses, "keypoint labels: inconsistent sizes");
  quantized_ = std::move(quantized);
  labeled_ = std::move(labeled);
}

}  // namespace semslam
