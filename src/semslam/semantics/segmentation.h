#pragma once
// The result of segmenting one image: a distribution over the 19 classes that can be sampled at any
// (sub-)pixel of the input image. Stored compactly at the resolution the segmenter produced it (for a CNN,
// its output resolution; for label images, theirs) together with the mapping back to input pixels, either as
//  - per-pixel log-probabilities (CV_32FC(19), pixel-major: 19 contiguous floats per pixel), or
//  - per-pixel labels (CV_8U trainIds, kNoLabel = none), optionally with a per-pixel confidence (CV_8U,
//    p = value / 255), turned into distributions by the confusion model: the given class gets alpha (or p),
//    the other 18 share the rest evenly.
// Sampling is nearest-neighbour in the stored grid. A Segmentation shares its pixel buffers when copied and
// never modifies them: it may be read from any number of threads.

#include <array>
#include <cstddef>
#include <cstdint>
#include <opencv2/core/mat.hpp>
#include <span>
#include <vector>

#include "semslam/geometry/eigen_types.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

// Log-probabilities over the 19 classes (trainId order).
using ClassLogProbs = std::array<float, kNumClasses>;

// The smallest probability an observation gives any class (log of 1e-4): one confident but wrong observation
// must not veto a class forever.
inline constexpr float kMinObservationProbability = 1e-4f;
inline constexpr float kMinObservationLogProbability = -9.210340372f;  // log(1e-4)

// The confusion model for a label-only observation: log(alpha) for `label`, log((1 - alpha) / 18) for the
// others, both floored at kMinObservationLogProbability. alpha must lie in [1/19, 1].
ClassLogProbs ConfusionLogProbs(int label, float alpha);

// What per-class score planes hold (see SegmentationFromScores).
enum class ScoreKind { kLogits, kProbabilities, kLogProbabilities };

class Segmentation {
 public:
  enum class Storage { kEmpty, kLogProbabilities, kLabels };

  Segmentation() = default;

  // `log_probabilities`: CV_32FC(19), normalized per pixel; a pixel whose 19 values are all 0 has no label.
  // It covers an input image of `input_size` (stretched over it when the sizes differ). Values are floored at
  // kMinObservationLogProbability (in place: the buffer is taken over). Throws InvalidArgument on a wrong
  // type or empty sizes.
  static Segmentation FromLogProbabilities(cv::Mat log_probabilities, cv::Size input_size);
  // `labels`: CV_8U trainIds (kNoLabel and any value >= 19 mean "no observation"). `confidence`: empty, or
  // CV_8U of the same size with the probability of the given label times 255 (replaces alpha per pixel;
  // clamped to [1/19, 1]). Throws InvalidArgument on wrong types or sizes, or alpha outside [1/19, 1].
  static Segmentation FromLabels(cv::Mat labels, cv::Size input_size, float alpha, cv::Mat confidence = {});

  Storage storage() const { return storage_; }
  bool empty() const { return storage_ == Storage::kEmpty; }
  // Size of the image that was segmented: sample coordinates refer to it.
  cv::Size input_size() const { return input_size_; }
  // Size of the stored grid.
  cv::Size storage_size() const { return data_.size(); }
  // Alpha of the confusion model (label storage).
  float alpha() const { return alpha_; }

  // Writes the 19 log-probabilities observed at input pixel (x, y) (pixel centres at integers) into
  // `log_probs` and returns true; returns false, leaving `log_probs` untouched, when the pixel lies outside
  // the input image or has no label. Cheap (a few ns): no allocation, no logarithm.
  bool Sample(float x, float y, float* log_probs) const {
    const int index = StorageIndex(x, y);
    if (index < 0) return false;
    return SampleIndex(index, log_probs);
  }
  bool Sample(const Eigen::Vector2d& pixel, ClassLogProbs* log_probs) const {
    return Sample(static_cast<float>(pixel.x()), static_cast<float>(pixel.y()), log_probs->data());
  }
  // The most probable class at an input pixel, kNoLabel when none (or outside the image).
  std::uint8_t LabelAt(float x, float y) const;

  // trainIds (CV_8U, kNoLabel = none) on the stored grid, and stretched to the input size (nearest).
  cv::Mat Labels() const;
  cv::Mat LabelsAtInputSize() const;
  // Probability of the most probable class (CV_32F) on the stored grid; 0 where there is no label.
  cv::Mat Confidence() const;
  // Labels plus per-pixel confidence (2 bytes a pixel instead of 76); itself when already labels.
  Segmentation Compacted() const;
  // Bytes held by the pixel buffers.
  size_t MemoryBytes() const;

  // The stored grid itself: CV_32FC(19) log-probabilities or CV_8U labels; and the CV_8U confidence, if any.
  const cv::Mat& data() const { return data_; }
  const cv::Mat& confidence_data() const { return confidence_; }

 private:
  // Index into the stored grid of the cell under input pixel (x, y); -1 outside.
  int StorageIndex(float x, float y) const {
    // NaN fails both comparisons.
    if (!(x >= -0.5f && x < max_x_ && y >= -0.5f && y < max_y_)) return -1;
    int sx = static_cast<int>((x + 0.5f) * scale_x_);
    int sy = static_cast<int>((y + 0.5f) * scale_y_);
    if (sx >= data_.cols) sx = data_.cols - 1;
    if (sy >= data_.rows) sy = data_.rows - 1;
    return sy * data_.cols + sx;
  }
  bool SampleIndex(int index, float* log_probs) const;
  void SetGeometry(cv::Size input_size);

  Storage storage_ = Storage::kEmpty;
  cv::Mat data_;
  cv::Mat confidence_;
  cv::Size input_size_;
  float scale_x_ = 1.0f, scale_y_ = 1.0f;  // stored cells per input pixel
  float max_x_ = 0.0f, max_y_ = 0.0f;      // input size - 0.5
  float alpha_ = 1.0f;
  // Label storage: the confusion-model rows for each label (alpha), and per confidence byte the log of the
  // given class's and of each other class's probability.
  std::vector<ClassLogProbs> label_rows_;
  std::vector<std::array<float, 2>> confidence_logs_;
};

// Builds a log-probability segmentation from per-channel score planes (each CV_32F, all of one size) of a
// network or a file. `channel_to_train_id[c]` is the trainId channel c stands for; several channels may map
// to one class (their probabilities add), and channels mapped to kNoLabel ("unlabeled") spread their
// probability evenly over the 19 classes: they say "no idea"; where they outweigh every class (ENet's
// 'unlabeled' on the ego vehicle, say) the pixel has no label at all. Logits go through a softmax;
// probabilities are renormalized.
Segmentation SegmentationFromScores(std::span<const cv::Mat> planes, ScoreKind kind,
                                    std::span<const std::uint8_t> channel_to_train_id, cv::Size input_size);

}  // namespace semslam
