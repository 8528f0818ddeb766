#include "semslam/eval/trajectory_metrics.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <system_error>

#include "semslam/core/error.h"
#include "semslam/geometry/alignment.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"

namespace semslam {

namespace fs = std::filesystem;

namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

void RequireIncreasing(const Trajectory& trajectory, const char* what) {
  for (size_t i = 1; i < trajectory.size(); ++i) {
    Require(trajectory[i].timestamp > trajectory[i - 1].timestamp,
            fmt::format("{} trajectory: timestamps must increase (pose {} at {} after {})", what, i,
                        trajectory[i].timestamp, trajectory[i - 1].timestamp));
  }
}

// Cumulative distance along the camera centres.
std::vector<double> Distances(const std::vector<Rigid3d>& poses) {
  std::vector<double> d(poses.size(), 0.0);
  for (size_t i = 1; i < poses.size(); ++i)
    d[i] = d[i - 1] + (poses[i].translation - poses[i - 1].translation).norm();
  return d;
}

double PathLengthOf(const std::vector<Rigid3d>& poses) {
  return poses.empty() ? 0.0 : Distances(poses).back();
}

// (truth_i^-1 truth_j)^-1 (estimate_i^-1 estimate_j).
Rigid3d RelativeError(const std::vector<Rigid3d>& estimate, const std::vector<Rigid3d>& truth, size_t i,
                      size_t j) {
  const Rigid3d delta_truth = truth[i].Inverse() * truth[j];
  const Rigid3d delta_estimate = estimate[i].Inverse() * estimate[j];
  return delta_truth.Inverse() * delta_estimate;
}

RelativeErrors Summarize(const std::vector<double>& trans, const std::vector<double>& rot_rad) {
  RelativeErrors r;
  r.pairs = trans.size();
  if (trans.empty()) return r;
  double st = 0, sr = 0;
  for (size_t k = 0; k < trans.size(); ++k) {
    st += trans[k] * trans[k];
    sr += rot_rad[k] * rot_rad[k];
  }
  r.trans_rmse_m = std::sqrt(st / static_cast<double>(trans.size()));
  r.rot_rmse_deg = std::sqrt(sr / static_cast<double>(trans.size())) * kRadToDeg;
  return r;
}

void FillAteStatistics(AteResult& ate) {
  const std::vector<double>& e = ate.errors;
  ate.matched = e.size();
  if (e.empty()) return;
  const double n = static_cast<double>(e.size());
  double sum = 0, sum_sq = 0;
  for (const double v : e) {
    sum += v;
    sum_sq += v * v;
  }
  ate.mean = sum / n;
  ate.rmse = std::sqrt(sum_sq / n);
  ate.std = std::sqrt(std::max(0.0, sum_sq / n - ate.mean * ate.mean));
  ate.max = *std::max_element(e.begin(), e.end());
  std::vector<double> sorted = e;
  std::sort(sorted.begin(), sorted.end());
  const size_t mid = sorted.size() / 2;
  ate.median = sorted.size() % 2 == 1 ? sorted[mid] : 0.5 * (sorted[mid - 1] + sorted[mid]);
}

struct Matched {
  std::vector<Rigid3d> estimate;
  std::vector<Rigid3d> truth;
};

Matched MatchPoses(const Trajectory& estimate, const Trajectory& truth, double max_dt) {
  const std::vector<PosePair> pairs = AssociateByTimestamp(estimate, truth, max_dt);
  if (pairs.empty()) {
    const auto range = [](const Trajectory& t) {
      return t.empty() ? std::string("no poses")
                       : fmt::format("{} poses, t = {:.6f}..{:.6f} s", t.size(), t.front().timestamp,
                                     t.back().timestamp);
    };
    throw EvaluationError(
        fmt::format("no estimated pose matched a ground-truth pose within {} s (estimate: {}; "
                    "ground truth: {})",
                    max_dt, range(estimate), range(truth)));
  }
  Matched m;
  for (const PosePair& p : pairs) {
    m.estimate.push_back(estimate[p.estimate].world_from_camera);
    m.truth.push_back(truth[p.truth].world_from_camera);
  }
  return m;
}

AteResult AteOfMatched(Matched& m, Alignment alignment) {
  const AlignmentResult aligned = AlignTrajectories(m.estimate, m.truth, alignment);
  AteResult ate;
  ate.truth_from_estimate = aligned.truth_from_estimate;
  ate.scale = aligned.truth_from_estimate.scale;
  ate.alignment_fallback = aligned.fallback;
  for (size_t i = 0; i < m.estimate.size(); ++i) {
    m.estimate[i] = aligned.truth_from_estimate.TransformPose(m.estimate[i]);
    ate.errors.push_back((m.estimate[i].translation - m.truth[i].translation).norm());
  }
  FillAteStatistics(ate);
  return ate;
}

}  // namespace

std::string_view AlignmentName(Alignment alignment) {
  switch (alignment) {
    case Alignment::kNone:
      return "none";
    case Alignment::kSe3:
      return "se3";
    case Alignment::kSim3:
      return "sim3";
  }
  return "?";
}

Alignment ParseAlignment(std::string_view name) {
  if (name == "none") return Alignment::kNone;
  if (name == "se3") return Alignment::kSe3;
  if (name == "sim3") return Alignment::kSim3;
  throw InvalidArgument(fmt::format("alignment '{}': expected sim3, se3 or none", name));
}

void EvalOptions::Check() const {
  Require(std::isfinite(max_dt) && max_dt >= 0, fmt::format("eval: max_dt = {} must be >= 0", max_dt));
  Require(std::isfinite(rpe_distance_m) && rpe_distance_m > 0,
          fmt::format("eval: rpe_distance_m = {} must be positive", rpe_distance_m));
  for (const double length : kitti_lengths_m) {
    Require(std::isfinite(length) && length > 0,
            fmt::format("eval: segment length {} must be positive", length));
  }
  Require(kitti_step >= 1, fmt::format("eval: kitti_step = {} must be >= 1", kitti_step));
}

std::vector<PosePair> AssociateByTimestamp(const Trajectory& estimate, const Trajectory& truth,
                                           double max_dt) {
  RequireIncreasing(estimate, "estimated");
  RequireIncreasing(truth, "ground-truth");
  std::vector<PosePair> pairs;
  std::vector<double> pair_dt;
  for (size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].timestamp;
    const auto it = std::lower_bound(truth.begin(), truth.end(), t,
                                     [](const StampedPose& p, double value) { return p.timestamp < value; });
    size_t best = truth.size();
    double best_dt = max_dt;
    for (const auto candidate : {it, it == truth.begin() ? truth.end() : std::prev(it)}) {
      if (candidate == truth.end()) continue;
      const double dt = std::abs(candidate->timestamp - t);
      if (dt <= best_dt) {
        best_dt = dt;
        best = static_cast<size_t>(candidate - truth.begin());
      }
    }
    if (best == truth.size()) continue;
    // Nearest truth indices never decrease: a repeat can only be the previous pair. Keep the closer one.
    if (!pairs.empty() && pairs.back().truth == best) {
      if (best_dt < pair_dt.back()) {
        pairs.back() = {i, best};
        pair_dt.back() = best_dt;
      }
      continue;
    }
    pairs.push_back({i, best});
    pair_dt.push_back(best_dt);
  }
  return pairs;
}

AlignmentResult AlignTrajectories(const std::vector<Rigid3d>& estimate, const std::vector<Rigid3d>& truth,
                                  Alignment alignment) {
  Require(estimate.size() == truth.size(), "AlignTrajectories: pose lists of different lengths");
  AlignmentResult result;
  if (alignment == Alignment::kNone || estimate.empty()) return result;
  Points3d src, tgt;
  for (size_t i = 0; i < estimate.size(); ++i) {
    src.push_back(estimate[i].translation);
    tgt.push_back(truth[i].translation);
  }
  if (alignment == Alignment::kSim3) {
    if (const auto sim = AlignSim3(src, tgt)) {
      result.truth_from_estimate = *sim;
      return result;
    }
  } else if (const auto rigid = AlignRigid3(src, tgt)) {
    result.truth_from_estimate = Sim3d(*rigid);
    return result;
  }
  // Degenerate: anchor the first pose.
  result.fallback = true;
  double scale = 1.0;
  if (alignment == Alignment::kSim3) {
    const double estimate_length = PathLengthOf(estimate);
    if (estimate_length > 0) scale = PathLengthOf(truth) / estimate_length;
    if (!(scale > 0) || !std::isfinite(scale)) scale = 1.0;
  }
  const Eigen::Quaterniond rotation = truth[0].rotation * estimate[0].rotation.conjugate();
  const Eigen::Vector3d translation = truth[0].translation - scale * (rotation * estimate[0].translation);
  result.truth_from_estimate = Sim3d(scale, rotation, translation);
  return result;
}

RelativeErrors ComputeConsecutiveRpe(const std::vector<Rigid3d>& estimate,
                                     const std::vector<Rigid3d>& truth) {
  Require(estimate.size() == truth.size(), "ComputeConsecutiveRpe: pose lists of different lengths");
  std::vector<double> trans, rot;
  for (size_t i = 0; i + 1 < estimate.size(); ++i) {
    const Rigid3d e = RelativeError(estimate, truth, i, i + 1);
    trans.push_back(e.translation.norm());
    rot.push_back(e.RotationAngle());
  }
  return Summarize(trans, rot);
}

std::optional<RelativeErrors> ComputeRpeOverDistance(const std::vector<Rigid3d>& estimate,
                                                     const std::vector<Rigid3d>& truth, double distance_m) {
  Require(estimate.size() == truth.size(), "ComputeRpeOverDistance: pose lists of different lengths");
  const std::vector<double> dist = Distances(truth);
  std::vector<double> trans, rot;
  size_t j = 0;
  for (size_t i = 0; i < dist.size(); ++i) {
    j = std::max(j, i);
    while (j < dist.size() && dist[j] - dist[i] < distance_m) ++j;
    if (j == dist.size()) break;
    const Rigid3d e = RelativeError(estimate, truth, i, j);
    trans.push_back(e.translation.norm());
    rot.push_back(e.RotationAngle());
  }
  if (trans.empty()) return std::nullopt;
  return Summarize(trans, rot);
}

KittiErrors ComputeKittiErrors(const std::vector<Rigid3d>& estimate, const std::vector<Rigid3d>& truth,
                               const std::vector<double>& lengths_m, int step) {
  Require(estimate.size() == truth.size(), "ComputeKittiErrors: pose lists of different lengths");
  Require(step >= 1, "ComputeKittiErrors: step must be >= 1");
  const std::vector<double> dist = Distances(truth);
  KittiErrors result;
  std::vector<double> sum_t(lengths_m.size(), 0.0), sum_r(lengths_m.size(), 0.0);
  std::vector<size_t> count(lengths_m.size(), 0);
  double total_t = 0, total_r = 0;
  for (size_t first = 0; first < dist.size(); first += static_cast<size_t>(step)) {
    for (size_t l = 0; l < lengths_m.size(); ++l) {
      const double target = dist[first] + lengths_m[l];
      const auto it = std::lower_bound(dist.begin() + static_cast<std::ptrdiff_t>(first), dist.end(), target);
      if (it == dist.end()) continue;
      const size_t last = static_cast<size_t>(it - dist.begin());
      // The devkit's error: (estimate delta)^-1 (truth delta).
      const Rigid3d delta_truth = truth[first].Inverse() * truth[last];
      const Rigid3d delta_estimate = estimate[first].Inverse() * estimate[last];
      const Rigid3d error = delta_estimate.Inverse() * delta_truth;
      const double t_err = error.translation.norm() / lengths_m[l];
      const double r_err = error.RotationAngle() / lengths_m[l];
      sum_t[l] += t_err;
      sum_r[l] += r_err;
      ++count[l];
      total_t += t_err;
      total_r += r_err;
      ++result.segments;
    }
  }
  for (size_t l = 0; l < lengths_m.size(); ++l) {
    if (count[l] == 0) continue;
    const double n = static_cast<double>(count[l]);
    result.per_length.push_back(
        {lengths_m[l], count[l], 100.0 * sum_t[l] / n, 100.0 * kRadToDeg * sum_r[l] / n});
  }
  if (result.segments > 0) {
    const double n = static_cast<double>(result.segments);
    result.trans_pct = 100.0 * total_t / n;
    result.rot_deg_per_100m = 100.0 * kRadToDeg * total_r / n;
  }
  return result;
}

TrajectoryEvaluation EvaluateTrajectory(const Trajectory& estimate, const Trajectory& truth,
                                        const EvalOptions& options) {
  options.Check();
  Matched m = MatchPoses(estimate, truth, options.max_dt);
  TrajectoryEvaluation result;
  result.alignment = options.alignment;
  result.estimate_poses = estimate.size();
  result.truth_poses = truth.size();
  result.matched = m.estimate.size();
  result.path_length_m = PathLengthOf(m.truth);
  result.ate = AteOfMatched(m, options.alignment);  // aligns m.estimate in place
  if (m.estimate.size() >= 2) result.rpe = ComputeConsecutiveRpe(m.estimate, m.truth);
  result.rpe_distance = ComputeRpeOverDistance(m.estimate, m.truth, options.rpe_distance_m);
  result.kitti = ComputeKittiErrors(m.estimate, m.truth, options.kitti_lengths_m, options.kitti_step);
  return result;
}

AteResult ComputeAte(const Trajectory& estimate, const Trajectory& truth, Alignment alignment,
                     double max_dt) {
  Require(std::isfinite(max_dt) && max_dt >= 0, "ComputeAte: max_dt must be >= 0");
  Matched m = MatchPoses(estimate, truth, max_dt);
  return AteOfMatched(m, alignment);
}

namespace {

// The ground truth of an opened sequence folder; InputError naming the folder when its reader has none.
Trajectory GroundTruthOf(const ImageSequence& opened, const fs::path& sequence) {
  std::optional<Trajectory> truth = opened.GroundTruth();
  if (!truth) {
    throw InputError(sequence,
                     "the sequence has no ground truth (a KITTI odometry sequence needs "
                     "poses/<name>.txt two folders up, a KITTI raw drive its oxts/ folder)");
  }
  return std::move(*truth);
}

}  // namespace

Trajectory ReadSequenceGroundTruth(const fs::path& sequence, const std::string& camera) {
  return GroundTruthOf(*OpenSequence(sequence, {camera, false}), sequence);
}

ErrorSeries ComputeErrorSeries(const Trajectory& estimate, const Trajectory& truth, Alignment alignment,
                               double max_dt) {
  Require(std::isfinite(max_dt) && max_dt >= 0, "ComputeErrorSeries: max_dt must be >= 0");
  Matched m = MatchPoses(estimate, truth, max_dt);
  ErrorSeries series;
  series.ate = AteOfMatched(m, alignment);  // aligns m.estimate in place
  series.distance_m = Distances(m.truth);
  series.rpe_trans_m.assign(m.estimate.size(), 0.0);
  for (size_t i = 1; i < m.estimate.size(); ++i) {
    series.rpe_trans_m[i] = RelativeError(m.estimate, m.truth, i - 1, i).translation.norm();
  }
  if (m.estimate.size() >= 2) series.rpe = ComputeConsecutiveRpe(m.estimate, m.truth);
  series.aligned = std::move(m.estimate);
  series.truth = std::move(m.truth);
  return series;
}

namespace {

std::string RangeText(size_t first, size_t end) { return fmt::format("frames {}:{}", first, end); }

// KITTI poses stamped by frame: times[first + i] (or first + i without times) for line i.
Trajectory StampKittiPoses(const std::vector<Rigid3d>& poses, size_t first,
                           const std::optional<std::vector<double>>& times) {
  Trajectory trajectory;
  trajectory.reserve(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) {
    trajectory.push_back({times ? (*times)[first + i] : static_cast<double>(first + i), poses[i]});
  }
  return trajectory;
}

}  // namespace

TrajectoryEvaluation EvaluateTrajectoryFiles(const fs::path& estimate, const fs::path& truth,
                                             const std::optional<fs::path>& times, const EvalOptions& options,
                                             const FrameRange& frames, const std::string& truth_camera) {
  options.Check();
  Require(!frames.end || frames.first < *frames.end,
          fmt::format("frames {}:{}: the range is empty", frames.first, frames.end.value_or(0)));
  std::error_code ec;
  const bool truth_is_sequence = fs::is_directory(truth, ec);
  if (!truth_is_sequence && !truth_camera.empty()) {
    throw InputError(
        truth, fmt::format("a camera ('{}') applies only when the truth is a sequence folder", truth_camera));
  }
  const TrajectoryFormat estimate_format = DetectTrajectoryFormat(estimate);
  const TrajectoryFormat truth_format =
      truth_is_sequence ? TrajectoryFormat::kTum : DetectTrajectoryFormat(truth);
  // A sequence folder as the truth is opened once, for its ground truth and, for a KITTI estimate, its stamps.
  const std::unique_ptr<ImageSequence> sequence =
      truth_is_sequence ? OpenSequence(truth, {truth_camera, false}) : nullptr;
  std::optional<std::vector<double>> stamps;
  if (times) {
    stamps = ReadTimes(*times);
  } else if (sequence && estimate_format == TrajectoryFormat::kKitti) {
    stamps = FrameTimestamps(*sequence, 0, sequence->size());  // line i is frame i of that sequence
  } else if (estimate_format != truth_format) {
    const fs::path& kitti = estimate_format == TrajectoryFormat::kKitti ? estimate : truth;
    const fs::path& tum = estimate_format == TrajectoryFormat::kTum ? estimate : truth;
    throw InputError(kitti,
                     fmt::format("KITTI poses carry no timestamps: give the sequence's times.txt (--times) "
                                 "to match them against the TUM file {}",
                                 tum.string()));
  }
  // Where the stamps come from, for messages.
  const std::string stamps_source =
      times ? times->filename().string() : fmt::format("the sequence {}", truth.string());

  // The frames the KITTI files cover: [first, end), end from the ground truth (KITTI) or the times.
  const size_t first = frames.first;
  std::optional<size_t> available;  // frames known: ground-truth lines (KITTI) and stamps
  if (truth_format == TrajectoryFormat::kKitti) available = CountKittiPoses(truth);
  if (stamps) available = std::min(available.value_or(stamps->size()), stamps->size());
  const bool uses_frames =
      estimate_format == TrajectoryFormat::kKitti || truth_format == TrajectoryFormat::kKitti;
  size_t end = frames.end.value_or(available.value_or(0));
  if (uses_frames && available && end > *available) {
    const fs::path& source = truth_format == TrajectoryFormat::kKitti || !times ? truth : *times;
    throw InputError(source, fmt::format("{} asked, but it covers only {} frames", RangeText(first, end),
                                         *available));
  }

  Trajectory truth_trajectory;
  if (truth_format == TrajectoryFormat::kKitti) {
    std::vector<Rigid3d> poses = ReadKittiPoses(truth);
    if (first >= end) {
      throw InputError(truth, fmt::format("holds {} poses: none in {}", poses.size(), RangeText(first, end)));
    }
    poses = std::vector<Rigid3d>(poses.begin() + static_cast<std::ptrdiff_t>(first),
                                 poses.begin() + static_cast<std::ptrdiff_t>(end));
    truth_trajectory = StampKittiPoses(poses, first, stamps);
  } else {
    truth_trajectory = sequence ? GroundTruthOf(*sequence, truth) : ReadTumTrajectory(truth);
  }

  Trajectory estimate_trajectory;
  if (estimate_format == TrajectoryFormat::kKitti) {
    const std::vector<Rigid3d> poses = ReadKittiPoses(estimate);
    const size_t expected = end > first ? end - first : 0;
    if (poses.size() != expected) {
      const std::string against =
          truth_format == TrajectoryFormat::kKitti
              ? fmt::format("the ground truth {} has {} in {}", truth.filename().string(), expected,
                            RangeText(first, end))
              : fmt::format("{} lists {} stamps in {}", stamps_source, expected, RangeText(first, end));
      throw InputError(
          estimate,
          fmt::format("holds {} poses but {}: a KITTI pose file has no timestamps (line i is frame {}), so it "
                      "needs exactly one line per frame or every pose after a gap is paired with the wrong "
                      "frame; give the frames the run covered (--frames A:B) or compare its TUM trajectory",
                      poses.size(), against, first == 0 ? std::string("i") : fmt::format("{} + i", first)));
    }
    estimate_trajectory = StampKittiPoses(poses, first, stamps);
  } else {
    estimate_trajectory = ReadTumTrajectory(estimate);
  }
  try {
    return EvaluateTrajectory(estimate_trajectory, truth_trajectory, options);
  } catch (const EvaluationError& e) {
    throw InputError(estimate, fmt::format("{} (ground truth {})", e.what(), truth.string()));
  }
}

}  // namespace semslam
