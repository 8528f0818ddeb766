#pragma once
// A map point's nearest labelled neighbours as one more observation of its class. A point whose own evidence
// is weak (one observation, or two that disagree: a tie) takes the class its confident neighbours agree on;
// a confident point is left alone. The neighbourhood votes from the labels as they were before any point is
// changed, so the result does not depend on the order of the points.

#include <cstddef>
#include <span>

#include "semslam/geometry/eigen_types.h"
#include "semslam/semantics/label_fusion.h"

namespace semslam {

struct NeighbourLabelOptions {
  int neighbours = 8;          // nearest labelled points consulted
  float confident = 0.9f;      // a point votes when its label's posterior is at least this; below it, it is helped
  int min_votes = 4;           // voting neighbours needed
  double agreement = 0.75;     // share of the votes the neighbourhood's class must have
  float alpha = 0.75f;         // the neighbourhood's observation: the confusion model with this alpha...
  float weight = 1.5f;         // ...counted as this many observations (more than one breaks a tie of two)
  void Check() const;
};

// positions[i] is the point whose posterior is *labels[i] (points without observations are skipped). Returns
// the number of points that received the neighbourhood's observation. Throws InvalidArgument on mismatched
// sizes or bad options.
size_t FuseNeighbourLabels(std::span<const Eigen::Vector3d> positions, std::span<LabelDistribution* const> labels,
                           const NeighbourLabelOptions& options = {});

}  // namespace semslam
