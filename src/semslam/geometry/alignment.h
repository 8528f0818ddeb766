#pragma once
// Closed-form alignment of corresponding point sets (Umeyama 1991): the similarity or rigid
// transform `tgt_from_src` minimizing sum_i w_i |tgt_i - T src_i|^2.

#include <optional>
#include <vector>

#include "semslam/geometry/sim3.h"

namespace semslam {

// Sim(3) (with scale). Returns nullopt with fewer than 3 pairs, mismatched sizes, or a degenerate
// (collinear or coincident) source set. `weights` may be empty (all 1) or hold one non-negative value per pair.
std::optional<Sim3d> AlignSim3(const Points3d& src, const Points3d& tgt, const std::vector<double>& weights = {});
// SE(3) (scale fixed to 1).
std::optional<Rigid3d> AlignRigid3(const Points3d& src, const Points3d& tgt, const std::vector<double>& weights = {});

// Root mean square of |tgt_i - T src_i|.
double AlignmentRmse(const Sim3d& tgt_from_src, const Points3d& src, const Points3d& tgt);

}  // namespace semslam
