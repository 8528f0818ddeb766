#include "semslam/geometry/scale_across_gap.h"

#include <Eigen/Dense>

#include "semslam/core/error.h"

namespace semslam {

namespace {

struct SpeedSample {
  double timestamp;  // the middle of its step
  double speed;      // units per second
};

std::vector<SpeedSample> StepSpeeds(const Trajectory& trajectory) {
  const Points3d centres = Positions(trajectory);
  std::vector<SpeedSample> samples;
  for (size_t i = 1; i < trajectory.size(); ++i) {
    const double seconds = trajectory[i].timestamp - trajectory[i - 1].timestamp;
    Require(seconds >= 0.0, "FitScaleAcrossGap: poses out of time order");
    if (seconds == 0.0) continue;
    samples.push_back({0.5 * (trajectory[i].timestamp + trajectory[i - 1].timestamp),
                       (centres[i] - centres[i - 1]).norm() / seconds});
  }
  return samples;
}

}  // namespace

std::optional<double> FitScaleAcrossGap(const Trajectory& before, const Trajectory& after) {
  const std::vector<SpeedSample> speeds_before = StepSpeeds(before), speeds_after = StepSpeeds(after);
  if (speeds_before.size() < 2 || speeds_after.size() < 2) return std::nullopt;
  const double gap_start = before.back().timestamp, gap_end = after.front().timestamp;
  Require(gap_end >= gap_start, "FitScaleAcrossGap: the side after the gap starts before the other ends");
  const double middle = 0.5 * (gap_start + gap_end);

  // Unknowns: the speed at the gap's middle v, the acceleration a (units before the gap) and the ratio s.
  // Before: v + a (t - middle) = speed; after: v + a (t - middle) - s * speed = 0.
  const int rows = static_cast<int>(speeds_before.size() + speeds_after.size());
  Eigen::MatrixX3d design(rows, 3);
  Eigen::VectorXd observed(rows);
  int row = 0;
  for (const SpeedSample& sample : speeds_before) {
    design.row(row) << 1.0, sample.timestamp - middle, 0.0;
    observed(row++) = sample.speed;
  }
  for (const SpeedSample& sample : speeds_after) {
    design.row(row) << 1.0, sample.timestamp - middle, -sample.speed;
    observed(row++) = 0.0;
  }
  // Standing still after the gap leaves the ratio's column zero: rank 2.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixX3d> qr(design);
  if (qr.rank() < 3) return std::nullopt;
  const Eigen::Vector3d solution = qr.solve(observed);
  const double speed_middle = solution(0), scale = solution(2);
  if (!(scale > 0.0) || !(speed_middle > 0.0)) return std::nullopt;
  return scale;
}

}  // namespace semslam
