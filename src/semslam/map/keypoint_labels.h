#pragma once
// The class observations of a segmented keyframe at its keypoints: 19 log-probabilities per keypoint, kept so
// that map points which gain an observation in this keyframe later (new triangulations, fusion, loop closing)
// still fuse what the segmentation said there. Quantized to a byte per class (1/16 nat steps down to -15.9,
// below the fusion's floor of log(1e-4)): a keyframe with 2000 keypoints holds 38 KB instead of 152 KB.

#include <cstdint>
#include <vector>

#include "semslam/semantics/segmentation.h"

namespace semslam {

class KeypointLabels {
 public:
  static constexpr float kStep = 1.0f / 16.0f;  // nats per quantization step

  bool empty() const { return labeled_.empty(); }
  size_t size() const { return labeled_.size(); }
  // From sampled rows (semantics/label_fusion.h SampleAtKeypoints: 19 floats per keypoint, an all-zero row
  // meaning no observation there).
  void Assign(const std::vector<float>& rows);
  // The observation at a keypoint; false when the keyframe is not segmented or has none there.
  bool Get(size_t keypoint, ClassLogProbs* log_probs) const;
  bool Has(size_t keypoint) const { return keypoint < labeled_.size() && labeled_[keypoint] != 0; }

  // Storage (map files).
  const std::vector<std::uint8_t>& quantized() const { return quantized_; }
  const std::vector<std::uint8_t>& labeled() const { return labeled_; }
  // Throws InvalidArgument when the sizes disagree.
  void Restore(std::vector<std::uint8_t> quantized, std::vector<std::uint8_t> labeled);

 private:
  std::vector<std::uint8_t> quantized_;  // kNumClasses per keypoint
  std::vector<std::uint8_t> labeled_;    // 1 where the keypoint has an observation
};

}  // namespace semslam
