#pragma once
// How right the map's labels are, on sequences with ground-truth label images (the synthetic city):
//  - single-frame: the segmentation's most probable class at each keypoint of each segmented keyframe against
//    the true label there;
//  - fused: each map point's fused label against the class of the surface it lies on, which is the true label
//    at its keypoints in the keyframes that observe it (the most frequent one). This judges the point by what
//    its feature was detected on, independent of how accurately the point was triangulated (a point a few
//    centimetres off a 15 cm curb would otherwise be judged against the wrong surface).

#include <array>
#include <cstdint>
#include <filesystem>

#include "semslam/map/map.h"
#include "semslam/semantics/class_table.h"

namespace semslam {

struct ClassAccuracyCounts {
  std::array<std::uint64_t, kNumClasses> evaluated{};  // by true class
  std::array<std::uint64_t, kNumClasses> correct{};
  std::uint64_t total_evaluated = 0;
  std::uint64_t total_correct = 0;

  void Add(int truth, bool right) {
    ++evaluated[static_cast<size_t>(truth)];
    ++total_evaluated;
    if (right) {
      ++correct[static_cast<size_t>(truth)];
      ++total_correct;
    }
  }
  double Accuracy() const {
    return total_evaluated ? static_cast<double>(total_correct) / static_cast<double>(total_evaluated) : 0.0;
  }
};

struct SemanticEvaluation {
  ClassAccuracyCounts single_frame;    // keypoints of segmented keyframes
  ClassAccuracyCounts fused;           // map points with a label and a true class
  std::uint64_t points_unlabeled = 0;  // map points with a true class but no fused label
  std::uint64_t keyframes = 0;         // segmented keyframes evaluated
};

// `label_dir` holds the true trainId images (%06d.png by frame index). Read lock on the map inside. Throws
// InputError naming a label image that is missing or of the wrong size.
SemanticEvaluation EvaluateSemantics(const Map& map, const std::filesystem::path& label_dir);

}  // namespace semslam
