#pragma once
// Trajectory accuracy against ground truth: ATE after alignment (Umeyama, Sim(3) or SE(3), or none), RPE
// between consecutive matched poses and over a travelled distance, and the KITTI odometry devkit's segment
// errors.
//
// Poses are matched by timestamp (nearest ground-truth pose within max_dt, each used at most once). The
// estimate is aligned to the ground truth once (truth_from_estimate) and every metric is computed on the
// aligned estimate; relative errors do not depend on the rigid part of the alignment, only on its scale (so
// Sim(3) evaluates a monocular run at its best global scale, and SE(3) / none reproduce the devkit's
// numbers).

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/geometry/sim3.h"
#include "semslam/geometry/trajectory.h"

namespace semslam {

enum class Alignment { kNone, kSe3, kSim3 };
std::string_view AlignmentName(Alignment alignment);  // "none", "se3", "sim3"
// Parses "none", "se3" or "sim3"; throws InvalidArgument otherwise.
Alignment ParseAlignment(std::string_view name);

// Trajectories that cannot be compared (no pose matched).
class EvaluationError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct EvalOptions {
  Alignment alignment = Alignment::kSim3;
  double max_dt = 0.02;           // s: largest timestamp difference of a matched pair
  double rpe_distance_m = 100.0;  // RPE over this distance along the ground truth
  std::vector<double> kitti_lengths_m = {100, 200, 300, 400, 500, 600, 700, 800};
  int kitti_step = 10;  // segments start at every kitti_step-th matched pose

  void Check() const;  // throws InvalidArgument
};

// Index pairs of matched poses, in time order; each estimate and truth pose appears at most once.
struct PosePair {
  size_t estimate = 0;
  size_t truth = 0;
};
// Both trajectories must be in increasing time order (InvalidArgument otherwise).
std::vector<PosePair> AssociateByTimestamp(const Trajectory& estimate, const Trajectory& truth,
                                           double max_dt);

// truth_from_estimate by Umeyama over the matched positions. With fewer than 3 pairs or degenerate positions
// (all equal or on one line, where the rotation about the line is undetermined) it falls back to anchoring
// the first estimate pose on the first truth pose, with scale = truth path length / estimate path length for
// Sim(3), and sets `fallback`.
struct AlignmentResult {
  Sim3d truth_from_estimate;
  bool fallback = false;
};
AlignmentResult AlignTrajectories(const std::vector<Rigid3d>& estimate, const std::vector<Rigid3d>& truth,
                                  Alignment alignment);

struct AteResult {
  double rmse = 0, mean = 0, median = 0, std = 0, max = 0;  // metres
  double scale = 1.0;                                       // of truth_from_estimate
  Sim3d truth_from_estimate;
  bool alignment_fallback = false;
  size_t matched = 0;
  std::vector<double> errors;  // per matched pose, metres
};

// Relative pose errors E = (truth_i^-1 truth_j)^-1 (estimate_i^-1 estimate_j) over pairs (i, j).
struct RelativeErrors {
  size_t pairs = 0;
  double trans_rmse_m = 0;
  double rot_rmse_deg = 0;
};

// The KITTI devkit's measure for one segment length, averaged over its segments.
struct KittiSegmentStats {
  double length_m = 0;
  size_t count = 0;
  double trans_pct = 0;         // translation error / length, percent
  double rot_deg_per_100m = 0;  // rotation error / length
};
struct KittiErrors {
  size_t segments = 0;
  std::optional<double> trans_pct;            // mean over all segments; nullopt when the path is too short
  std::optional<double> rot_deg_per_100m;     // mean over all segments
  std::vector<KittiSegmentStats> per_length;  // lengths with at least one segment
};

struct TrajectoryEvaluation {
  Alignment alignment = Alignment::kSim3;
  size_t estimate_poses = 0;
  size_t truth_poses = 0;
  size_t matched = 0;
  double path_length_m = 0;  // of the matched ground-truth poses
  AteResult ate;
  std::optional<RelativeErrors> rpe;           // consecutive matched poses (nullopt with < 2 matches)
  std::optional<RelativeErrors> rpe_distance;  // over options.rpe_distance_m (nullopt on a shorter path)
  KittiErrors kitti;
};

// On equally long lists of matched poses (the estimate already aligned):
RelativeErrors ComputeConsecutiveRpe(const std::vector<Rigid3d>& estimate, const std::vector<Rigid3d>& truth);
std::optional<RelativeErrors> ComputeRpeOverDistance(const std::vector<Rigid3d>& estimate,
                                                     const std::vector<Rigid3d>& truth, double distance_m);
// Devkit method: from every step-th pose, for each length the first pose at least that far along the ground
// truth path; error E = (estimate_i^-1 estimate_j)^-1 (truth_i^-1 truth_j), |t(E)| / length and angle(E) /
// length.
KittiErrors ComputeKittiErrors(const std::vector<Rigid3d>& estimate, const std::vector<Rigid3d>& truth,
                               const std::vector<double>& lengths_m, int step);

// Matches, aligns and measures. Throws EvaluationError when no pose matched.
TrajectoryEvaluation EvaluateTrajectory(const Trajectory& estimate, const Trajectory& truth,
                                        const EvalOptions& options = {});
// ATE only (what `semslam run` reports). Throws EvaluationError when no pose matched.
AteResult ComputeAte(const Trajectory& estimate, const Trajectory& truth, Alignment alignment,
                     double max_dt = 0.02);

// Per matched pose, for plots of the errors along the drive (as evo_ape / evo_rpe draw them).
struct ErrorSeries {
  AteResult ate;                       // errors[i]: the ATE of matched pose i
  std::vector<Rigid3d> aligned;        // matched estimate poses, aligned to the ground truth (truth_from_estimate)
  std::vector<Rigid3d> truth;          // matched ground-truth poses
  std::vector<double> distance_m;      // along the matched ground truth, at pose i
  std::vector<double> rpe_trans_m;     // |t(E)| from pose i-1 to pose i (rpe_trans_m[0] = 0, not counted)
  RelativeErrors rpe;                  // consecutive pairs
};
// Throws EvaluationError when no pose matched.
ErrorSeries ComputeErrorSeries(const Trajectory& estimate, const Trajectory& truth, Alignment alignment,
                               double max_dt = 0.02);

// The frames a KITTI pose file covers: line i is frame first + i. Only KITTI files have no timestamps of their
// own; TUM files are matched by time whatever the range.
struct FrameRange {
  size_t first = 0;
  std::optional<size_t> end;  // exclusive; default: as many frames as the ground truth (or times) has
};

// Reads two trajectory files (TUM or KITTI, see io/trajectory_io.h) and evaluates them. KITTI files take
// their timestamps from `times` when given (line i: the stamp of frame frames.first + i), else their frame
// index; a TUM file cannot be matched against a KITTI file without `times`. A KITTI ground truth is used over
// `frames`. A KITTI estimate must hold exactly one pose per frame it is compared with (the ground truth's
// frames in the range when that is a KITTI file, else the stamps of `times` in the range): a missing line
// would pair every later pose with the wrong frame, so the files are refused with the reason. The truth may
// also be a sequence folder whose reader has a ground truth (io/sequence.h: a KITTI odometry sequence with
// poses/, a KITTI raw drive with oxts/, the synthetic city), for its camera `truth_camera` (empty: the
// default one), stamped with the sequence's timestamps; a KITTI estimate then takes the sequence's frame
// stamps when no `times` are given. Throws InputError naming the files.
TrajectoryEvaluation EvaluateTrajectoryFiles(const std::filesystem::path& estimate,
                                             const std::filesystem::path& truth,
                                             const std::optional<std::filesystem::path>& times,
                                             const EvalOptions& options = {}, const FrameRange& frames = {},
                                             const std::string& truth_camera = {});
// The ground truth of a sequence folder (see EvaluateTrajectoryFiles). Throws InputError naming the folder
// when its reader has none.
Trajectory ReadSequenceGroundTruth(const std::filesystem::path& sequence, const std::string& camera = {});

}  // namespace semslam
