#pragma once
// Tying the SLAM map to the world (paper §III-C): (GPS, keyframe position) pairs sampled every N frames, and
// the similarity `enu_from_map` (Umeyama; SE(3) for metric stereo maps) that maps keyframe positions onto
// the fixes, robust to outlier fixes (RANSAC over minimal triples, then iteratively reweighted least squares
// with a Cauchy loss), re-estimated as samples arrive. Fixes on one line (a straight drive) leave the roll
// about it free: the cameras' down axis then sets it.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geo/gps.h"
#include "semslam/geometry/sim3.h"

namespace semslam {

// One (GPS, map position) pair.
struct GpsSample {
  size_t frame_index = 0;
  double timestamp = 0.0;
  Eigen::Vector3d map_position = Eigen::Vector3d::Zero();
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();  // the matched fix in the ENU frame
  double sigma_m = 1.0;
  size_t fix_index = 0;  // into the GpsLog's fixes
  Eigen::Vector3d camera_down = Eigen::Vector3d::Zero();  // the frame's (FramePosition::camera_down)
};

struct GpsSamplingOptions {
  // A sample is taken at the first frame (with a matched fix) at or after every N-th frame; the paper
  // uses 30.
  int every_n_frames = 30;
  // A frame matches the fix nearest in time within this tolerance (seconds).
  double match_tolerance_s = 0.05;
  // Added to frame times to reach the GPS time base (see GuessTimeOffset).
  double time_offset_s = 0.0;

  void Check() const;
};

// Samples pairs from frames in frame_index order (all frames, or only keyframes: sampling then takes the
// first keyframe at or after each N-th frame).
std::vector<GpsSample> SampleGpsPairs(const std::vector<FramePosition>& frames,
                                      const std::vector<GpsFix>& fixes, const EnuFrame& enu_frame,
                                      const GpsSamplingOptions& options);

// The same, one frame at a time (for a running SLAM).
class GpsSampler {
 public:
  GpsSampler(std::vector<GpsFix> fixes, EnuFrame enu_frame, GpsSamplingOptions options);
  // Returns the sample when this frame is taken. Frames must come in increasing frame_index order.
  std::optional<GpsSample> AddFrame(const FramePosition& frame);

 private:
  std::vector<GpsFix> fixes_;
  EnuFrame enu_frame_;
  GpsSamplingOptions options_;
  std::optional<size_t> next_frame_;
};

struct GpsAlignmentOptions {
  bool estimate_scale = true;  // Sim(3) for monocular maps; false: SE(3) (stereo, metric map)
  int min_samples = 4;         // fewer: no estimate
  // RANSAC over minimal triples (skipped, and only IRLS from all samples is used, when ransac_iterations =
  // 0).
  int ransac_iterations = 300;
  // A sample is an inlier when its residual is below max(inlier_threshold_m, inlier_sigma_factor * sigma,
  // inlier_mad_factor * robust spread of the residuals). The spread term keeps the inliers of a map whose
  // scale drifts (residuals of a few metres everywhere) while 50 m outliers still stand out.
  double inlier_threshold_m = 5.0;
  double inlier_sigma_factor = 3.0;
  double inlier_mad_factor = 4.0;
  // Iteratively reweighted least squares on the inliers: weight = Cauchy(r / (cauchy_scale * sigma)) /
  // sigma^2. The 3D residual of sigma-noise is about 1.6 sigma long: a scale of 4 keeps true inliers near
  // full weight (2 lost 0.1 m of ATE against least squares on the true inliers in the 50 m outlier test).
  int irls_iterations = 10;
  double cauchy_scale = 4.0;
  // Minimal triples whose smallest angle's sine is below this are degenerate (nearly collinear) and skipped.
  double min_triangle_sine = 0.05;
  // Map positions whose scatter's second principal axis is shorter than this fraction of the first are
  // (nearly) on one line.
  double min_spread_ratio = 0.01;
  // Positions on one line are placed along the line of the fixes, with the roll about it that turns the
  // samples' mean camera down axis (GpsSample::camera_down) nearest to the world's down: a car's camera
  // keeps its image rows level within the road's bank, a few degrees. False, or no camera axes: no estimate.
  bool roll_from_camera_down = true;
  // So are positions whose spread across their line (metres, RMS) is under this many fix sigmas (median):
  // a nearly straight road's bow in noisy fixes turns the roll that Umeyama finds by tens of degrees.
  double min_roll_spread_sigmas = 5.0;
  std::uint64_t seed = 1;

  void Check() const;
};

struct GpsAlignment {
  Sim3d enu_from_map;               // scale 1 when !estimate_scale
  std::vector<double> residuals_m;  // |enu_i - enu_from_map * map_i|, per sample
  std::vector<bool> inliers;        // per sample
  int num_inliers = 0;
  double inlier_rmse_m = 0.0;
  double rmse_m = 0.0;  // over all samples
  bool roll_from_camera_down = false;  // the positions lay on one line: the cameras set the roll about it
};

// Robust alignment; nullopt with fewer than min_samples samples, or when the positions are nearly on one line
// (min_spread_ratio, or no minimal triple passes min_triangle_sine: a straight drive leaves the roll about it
// undetermined) and the samples carry no camera axes to set it (roll_from_camera_down).
std::optional<GpsAlignment> AlignMapToGps(const std::vector<GpsSample>& samples,
                                          const GpsAlignmentOptions& options = {});
// The similarity (scale 1 without estimate_scale) that lays map positions on (nearly) one line onto the ENU
// positions' line, least squares along it, turned about it so that `map_down` (a camera down axis in the map
// frame) comes nearest to the world's down; nullopt when degenerate (a point, or down along the line).
std::optional<Sim3d> AlignAlongLine(const Points3d& map, const Points3d& enu, const Eigen::Vector3d& map_down,
                                    bool estimate_scale);
// Residuals and their statistics of a given transform (inlier flags: the threshold rule above).
GpsAlignment EvaluateAlignment(const Sim3d& enu_from_map, const std::vector<GpsSample>& samples,
                               const GpsAlignmentOptions& options = {});

// Samples as they arrive; the alignment re-estimated on every change.
class IncrementalGpsAligner {
 public:
  explicit IncrementalGpsAligner(GpsAlignmentOptions options = {});

  // Adds a sample and re-estimates; returns the current estimate (nullopt while too few samples).
  const std::optional<GpsAlignment>& Add(const GpsSample& sample);
  // After bundle adjustment or a loop closure moved keyframes: new map positions by frame_index (nullopt:
  // keep the sample's position; a culled keyframe can stay at its last known position). Re-estimates.
  const std::optional<GpsAlignment>& UpdateMapPositions(
      const std::function<std::optional<Eigen::Vector3d>(size_t frame_index)>& position_of);

  const std::vector<GpsSample>& samples() const { return samples_; }
  const std::optional<GpsAlignment>& current() const { return current_; }

 private:
  void Reestimate();

  GpsAlignmentOptions options_;
  std::vector<GpsSample> samples_;
  std::optional<GpsAlignment> current_;
};

}  // namespace semslam
