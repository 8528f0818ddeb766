#pragma once
// How right the map's labels are, on sequences with ground-truth label images (the synthetic city). Two
// measures of the fused map-point labels, named apart in run.json:
//  - 3D ("surface", EvaluateSemantics3d; run.json label_accuracy_3d): each map point is moved into the truth
//    frames of the keyframes around those that observe it and projected; in the frames where the true depth
//    there agrees with the point's depth (within 3 %: the camera sees the point's surface, not something in
//    front of or behind it), the true label is a vote; the majority is the class of the surface the point
//    lies on. Points near a class boundary in the truth (labels differ within 2 px, or the frames disagree)
//    are counted apart. Points no frame confirms (off every surface, or only on the sky) are "unverified".
//    Two alignments: per keyframe (its estimated camera onto its true camera; the headline) and global (one
//    Sim(3) of the trajectory against the ground truth for monocular runs, SE(3) for stereo;
//    label_accuracy_3d_global).
//  - 2D ("keypoints", EvaluateSemantics; label_accuracy_2d): the point's label against the true label at the
//    keypoints that observed it. It judges a point by what its feature was detected on, and so cannot see a
//    point triangulated onto the wrong surface; it reads higher.
// And one of the segmentation itself:
//  - single-frame: the segmentation's most probable class at each keypoint of each segmented keyframe against
//    the true label there.

#include <array>
#include <cstdint>
#include <filesystem>

#include "semslam/geometry/sim3.h"
#include "semslam/geometry/trajectory.h"
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

// The truth the 3D measure reads: per frame a trainId image and a depth image (uint16, metres * 256, 0 =
// sky), the true camera poses (matched to keyframes by timestamp), and the map's alignment with the truth
// frame.
struct SurfaceTruth {
  std::filesystem::path label_dir;
  std::filesystem::path depth_dir;
  Trajectory truth;  // world_from_camera per frame
  Sim3d truth_from_map;
  bool metric = true;  // the map is in metres (stereo); false: monocular, scale per keyframe
};

struct SurfaceEvaluationOptions {
  double depth_tolerance = 0.03;  // |point depth - true depth| <= this * true depth
  int boundary_radius = 2;        // pixels around the projection checked for another class
  int keyframe_window = 5;        // keyframes before and after a point's observing ones that check it
  void Check() const;
};

// The 3D measure under one way of placing the map in the truth frames.
struct SurfaceScores {
  ClassAccuracyCounts points;        // labelled points on a verified surface
  ClassAccuracyCounts off_boundary;  // those away from class boundaries
  ClassAccuracyCounts on_boundary;   // those on one
  // [true class][fused label] over `points`.
  std::array<std::array<std::uint64_t, kNumClasses>, kNumClasses> confusion{};
  std::uint64_t points_unverified = 0;  // labelled points no frame confirms (off every surface, or only sky)
  std::uint64_t points_unlabeled = 0;   // on a verified surface, without a fused label
};

struct SurfaceEvaluation {
  // Each keyframe's estimated camera put onto its true camera (monocular: at the keyframe's scale): a point
  // is judged where the cameras that built the map see it. The headline figure.
  SurfaceScores per_frame;
  // The whole map aligned once (the trajectory's Sim(3)/SE(3) against the truth): the trajectory's error then
  // moves each projection too (a few pixels), which at contact boundaries (a car on the road, a pole on the
  // sidewalk) flips the true class. A second figure.
  SurfaceScores global;
  std::uint64_t keyframes = 0;  // keyframes with a true pose, read
};

// Read lock on the map inside. Throws InputError naming a truth image that is missing or of the wrong size.
SurfaceEvaluation EvaluateSemantics3d(const Map& map, const SurfaceTruth& truth,
                                      const SurfaceEvaluationOptions& options = {});

}  // namespace semslam
