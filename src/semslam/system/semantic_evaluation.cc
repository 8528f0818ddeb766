#include "semslam/system/semantic_evaluation.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <unordered_map>

#include "semslam/core/error.h"

namespace semslam {
namespace {

cv::Mat ReadTrueLabels(const std::filesystem::path& label_dir, std::uint64_t frame,
                       const PinholeCamera& camera) {
  const std::filesystem::path path = label_dir / fmt::format("{:06d}.png", frame);
  cv::Mat labels = cv::imread(path.string(), cv::IMREAD_UNCHANGED);
  if (labels.empty()) throw InputError(path, "cannot read the ground-truth label image");
  if (labels.type() != CV_8UC1 || labels.cols != camera.width || labels.rows != camera.height) {
    throw InputError(path, fmt::format("expected an 8-bit {}x{} label image", camera.width, camera.height));
  }
  return labels;
}

int ArgMax(const ClassLogProbs& values) {
  return static_cast<int>(std::max_element(values.begin(), values.end()) - values.begin());
}

}  // namespace

SemanticEvaluation EvaluateSemantics(const Map& map, const std::filesystem::path& label_dir) {
  auto lock = map.ReadLock();
  SemanticEvaluation result;
  // Votes of the observing keyframes for each point's true class.
  std::unordered_map<const MapPoint*, std::array<std::uint16_t, kNumClasses>> votes;
  for (const KeyFrame* kf : map.KeyFrames()) {
    if (kf->keypoint_labels.empty()) continue;
    const cv::Mat truth = ReadTrueLabels(label_dir, kf->frame_id(), kf->camera());
    ++result.keyframes;
    const auto& keypoints = kf->features().keypoints;
    for (size_t i = 0; i < keypoints.size(); ++i) {
      const int u = std::clamp(static_cast<int>(std::lround(keypoints[i].pixel.x())), 0, truth.cols - 1);
      const int v = std::clamp(static_cast<int>(std::lround(keypoints[i].pixel.y())), 0, truth.rows - 1);
      const int true_class = truth.at<std::uint8_t>(v, u);
      if (!IsValidTrainId(true_class)) continue;
      ClassLogProbs observation;
      if (kf->keypoint_labels.Get(i, &observation))
        result.single_frame.Add(true_class, ArgMax(observation) == true_class);
      const MapPoint* point = kf->map_point(static_cast<int>(i));
      if (point != nullptr && !point->is_bad()) ++votes[point][static_cast<size_t>(true_class)];
    }
  }
  for (const auto& [point, counts] : votes) {
    const int true_class = static_cast<int>(std::max_element(counts.begin(), counts.end()) - counts.begin());
    const int label = point->labels().Label();
    if (!IsValidTrainId(label)) {
      ++result.points_unlabeled;
      continue;
    }
    result.fused.Add(true_class, label == true_class);
  }
  return result;
}

}  // namespace semslam
