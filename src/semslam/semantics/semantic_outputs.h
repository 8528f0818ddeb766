#pragma once
// What the semantic part writes and how it is scored: the semantic point cloud (PLY), per-class counts,
// map-point label accuracy against a ground-truth function, pixel accuracy / IoU of segmentations, colourized
// label images.

#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <span>
#include <vector>

#include "semslam/geometry/eigen_types.h"
#include "semslam/semantics/class_table.h"
#include "semslam/semantics/label_fusion.h"

namespace semslam {

struct SemanticPoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  int label = kNoLabel;     // trainId, or kNoLabel
  float confidence = 0.0f;  // posterior of the label
  int observations = 0;     // segmentations fused into it
};

// A map point's position and fused labels as written to the PLY (label kNoLabel while unobserved).
SemanticPoint ToSemanticPoint(const Eigen::Vector3d& position, const LabelDistribution& labels);

enum class PlyFormat { kBinary, kAscii };

// Writes a PLY point cloud with x, y, z (float), red, green, blue (uchar, class palette; black without a
// label), label (uchar trainId, 255 = none), confidence (float) and observations (int). Written atomically.
// Throws InvalidArgument for non-finite positions.
void WriteSemanticPly(const std::filesystem::path& path, std::span<const SemanticPoint> points,
                      PlyFormat format = PlyFormat::kBinary);
// Reads what WriteSemanticPly wrote (ASCII or binary little-endian; vertex properties in any order, unknown
// ones skipped; label/confidence/observations optional). Throws InputError naming the file and line.
std::vector<SemanticPoint> ReadSemanticPly(const std::filesystem::path& path);

// Points per class: index = trainId, index 19 = no label.
using ClassCounts = std::array<std::uint64_t, kNumClasses + 1>;
ClassCounts CountLabels(std::span<const SemanticPoint> points);
// Pixels per class of a trainId image (CV_8U): index = trainId, 19 = anything else.
ClassCounts CountLabels(const cv::Mat& train_ids);

// The true class of a map point, or nullopt where the truth does not say (e.g. no surface within tolerance).
using GroundTruthClassFn = std::function<std::optional<int>(const Eigen::Vector3d&)>;

struct LabelAccuracy {
  std::uint64_t evaluated = 0;  // labeled points with a true class
  std::uint64_t correct = 0;
  std::uint64_t unlabeled = 0;  // points with a true class but no label (not in `evaluated`)
  std::uint64_t no_truth = 0;   // points the truth says nothing about
  // Per true class: points evaluated and points labeled right (recall).
  std::array<std::uint64_t, kNumClasses> class_evaluated{};
  std::array<std::uint64_t, kNumClasses> class_correct{};

  double Accuracy() const {
    return evaluated ? static_cast<double>(correct) / static_cast<double>(evaluated) : 0.0;
  }
  // nullopt when no point of the class was evaluated.
  std::optional<double> ClassAccuracy(int train_id) const;
};
LabelAccuracy EvaluatePointLabels(std::span<const SemanticPoint> points, const GroundTruthClassFn& truth);

// Confusion matrix of segmentations against ground truth, accumulated over images (Cityscapes-style scoring:
// truth pixels without a class are ignored; a prediction without a class counts as wrong).
class SegmentationScore {
 public:
  // `predicted` and `truth`: CV_8U trainIds of one size. Throws InvalidArgument otherwise.
  void Add(const cv::Mat& predicted, const cv::Mat& truth);

  std::uint64_t pixels() const { return pixels_; }
  double PixelAccuracy() const;
  // IoU of a class; nullopt when the class appears in neither truth nor prediction.
  std::optional<double> ClassIou(int train_id) const;
  // Mean IoU over the classes present in truth or prediction (Cityscapes-style: a class predicted but absent
  // from the truth counts with IoU 0).
  double MeanIou() const;
  // Mean IoU over the classes present in the truth only.
  double MeanIouOverTruthClasses() const;
  // Confusion count: truth class t predicted as p (p = 19: no prediction).
  std::uint64_t Count(int truth, int predicted) const;

 private:
  std::array<std::array<std::uint64_t, kNumClasses + 1>, kNumClasses> confusion_{};
  std::uint64_t pixels_ = 0;
  std::uint64_t correct_ = 0;
};

// BGR image of the class palette (black where there is no class). With `image` (grey or BGR, same size), the
// colours are blended over it with weight `alpha`.
cv::Mat ColorizeLabels(const cv::Mat& train_ids, const cv::Mat& image = {}, double alpha = 0.6);

}  // namespace semslam
