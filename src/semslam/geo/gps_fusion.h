#pragma once
// GPS fixes as robust constraints in a pose graph (beyond the paper's single similarity, §III-C): the
// keyframe chain of a (monocular, scale-drifting) map is pre-aligned to ENU with the robust Sim(3) of the
// sampled (GPS, frame) pairs, then optimized as a Sim(3) pose graph (SE(3) for stereo) whose relative edges
// keep the map's local shape and whose position priors pull the sampled frames' GPS antennas to their fixes
// under a Cauchy loss, so that scale drift is corrected along the trajectory and outlier fixes lose their
// pull. Every fix enters the graph: the similarity only starts it. The Cauchy scale is graduated (Yang et al.
// 2020, graduated non-convexity): it starts wide enough that the fixes a drifting map lies far from still
// pull, and halves each solve down to `prior_loss_scale`, so the graph bends to what the fixes agree on
// before a fix far from it loses its pull. Fixes still off by more than `outlier_sigma` sigmas after that are
// dropped and the graph solved again.
//
// Nodes: every keyframe, plus every sampled frame that is not a keyframe (tied to the keyframes before and
// after it by the relative poses of the map). Edges: consecutive keyframes (from their poses, unless the
// caller gives an edge between them) and the caller's covisibility and loop edges (measured relative
// similarities, e.g. a loop's Sim(3)).

#include <optional>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geo/georeference.h"
#include "semslam/geo/gps.h"
#include "semslam/geo/gps_alignment.h"
#include "semslam/geometry/sim3.h"
#include "semslam/optim/pose_graph.h"

namespace semslam {

enum class FusionEdgeKind { kSequential, kCovisibility, kLoop };

// A relative constraint between keyframes a and b (indices into GpsFusionInput::keyframes):
// a_from_b = world_from_a^-1 * world_from_b as measured (map units; a loop's similarity may carry a scale).
struct FusionEdge {
  int a = 0, b = 0;
  Sim3d a_from_b;
  FusionEdgeKind kind = FusionEdgeKind::kCovisibility;
  double weight = 1.0;  // multiplies the edge's information (the sigmas below)
};

struct GpsFusionInput {
  std::vector<FramePose> keyframes;  // strictly increasing frame_index
  // Every tracked frame, for sampling every N frames as the paper does; empty: keyframes are sampled.
  std::vector<FramePose> frames;
  std::vector<FusionEdge> edges;
  std::vector<GpsFix> fixes;  // time-ordered (GpsLog::fixes)
  // Where the map already sits in the ENU frame (a map fused before): the graph starts there instead of at
  // the robust similarity of the samples.
  std::optional<Sim3d> enu_from_map;
};

struct GpsFusionOptions {
  GpsSamplingOptions sampling;
  GpsAlignmentOptions alignment;  // alignment.estimate_scale: Sim(3) nodes (monocular); false: SE(3) (stereo)
  // Edge precision: translation sigma = max(translation_sigma_fraction * |t_ab|, translation_sigma_floor_m),
  // rotation sigma per edge, and the log-scale sigma of a random walk: log_scale_sigma_per_sqrt_m times the
  // root of the edge's length in metres (at least translation_sigma_floor_m). Monocular scale drifts by up to
  // 5-7 % per 100 m on real drives (KITTI 00 with its published calibration); a tighter walk holds the map's
  // drift against the fixes.
  double translation_sigma_fraction = 0.01;
  double translation_sigma_floor_m = 0.02;
  double rotation_sigma_rad = 0.002;
  double log_scale_sigma_per_sqrt_m = 0.002;
  double prior_loss_scale = 2.0;  // Cauchy scale, in sigmas of the fix (the last of the graduated ones)
  // Fixes on (or near) one line leave the roll about it to the alignment's camera down axis; in the graph
  // only the antenna's lever arm and the map's attitude noise would bear on it, and it turns freely (KITTI
  // 04: 12.9 deg): every node's camera down axis is then held where the alignment put it (radians).
  double line_roll_sigma_rad = 0.05;
  double outlier_sigma = 5.0;     // a fix farther than this many sigmas from its fused frame is dropped
  int max_rounds = 3;             // solves after the graduated ones, each without the fixes dropped before
  // The GPS antenna in the camera frame (x right, y down, z forward), metres: a fix is where the antenna was.
  Eigen::Vector3d antenna_in_camera_m = Eigen::Vector3d::Zero();
  int max_iterations = 50;
  bool add_chain_edges = true;
  // Covisibility between keyframes of one pass restates the chain's scale from the same observations:
  // counted again with every edge, it holds a monocular map's scale drift against its fixes. By default
  // those edges keep the map's local shape and the chain alone carries its scale.
  bool one_pass_covisibility_carries_scale = false;

  void Check() const;  // throws InvalidArgument
};

struct GpsFusionResult {
  // Global similarity (the best fit of the map's node positions onto their fused ENU positions) with the
  // per-node corrections (LocalCorrections) that carry the fusion to every map point and frame.
  Georeference georeference;
  GpsAlignment prealignment;  // the robust Sim(3) of the samples (the paper's method, made robust)
  std::vector<GpsSample> samples;
  std::vector<double> residuals_m;  // |fused antenna position - fix| per sample
  std::vector<bool> inliers;        // fixes kept in the final solve
  int num_inliers = 0;
  double inlier_rmse_m = 0.0;
  std::vector<Sim3d> keyframe_enu_from_camera;  // fused keyframe poses (scale: metres per camera unit)
  int rounds = 0;
  PoseGraphSummary summary;  // of the last solve
};

// nullopt when the samples do not determine an alignment (too few, or all on one line). Throws
// InvalidArgument on bad options or inputs (unsorted keyframes, edge indices out of range).
std::optional<GpsFusionResult> FuseGps(const GpsFusionInput& input, const EnuFrame& enu_frame,
                                       const GpsFusionOptions& options = {});

}  // namespace semslam
