#include "semslam/geo/gps_alignment.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "semslam/core/error.h"
#include "semslam/geometry/alignment.h"

namespace semslam {

void GpsSamplingOptions::Check() const {
  Require(every_n_frames >= 1, "GPS every_n_frames must be at least 1");
  Require(std::isfinite(match_tolerance_s) && match_tolerance_s >= 0, "GPS match_tolerance_s must be >= 0");
  Require(std::isfinite(time_offset_s), "GPS time_offset_s must be finite");
}

void GpsAlignmentOptions::Check() const {
  Require(min_samples >= 3, "GPS alignment min_samples must be at least 3");
  Require(ransac_iterations >= 0, "GPS alignment ransac_iterations must be >= 0");
  Require(std::isfinite(inlier_threshold_m) && inlier_threshold_m > 0,
          "GPS inlier_threshold_m must be positive");
  Require(std::isfinite(inlier_sigma_factor) && inlier_sigma_factor >= 0,
          "GPS inlier_sigma_factor must be >= 0");
  Require(std::isfinite(inlier_mad_factor) && inlier_mad_factor >= 0, "GPS inlier_mad_factor must be >= 0");
  Require(irls_iterations >= 0, "GPS irls_iterations must be >= 0");
  Require(std::isfinite(cauchy_scale) && cauchy_scale > 0, "GPS cauchy_scale must be positive");
  Require(min_triangle_sine >= 0 && min_triangle_sine < 1, "GPS min_triangle_sine must be in [0, 1)");
  Require(min_spread_ratio >= 0 && min_spread_ratio < 1, "GPS min_spread_ratio must be in [0, 1)");
  Require(std::isfinite(min_roll_spread_sigmas) && min_roll_spread_sigmas >= 0,
          "GPS min_roll_spread_sigmas must be >= 0");
}

namespace {

GpsSample MakeSample(const FramePosition& frame, const std::vector<GpsFix>& fixes, size_t fix_index,
                     const EnuFrame& enu_frame) {
  GpsSample sample;
  sample.frame_index = frame.frame_index;
  sample.timestamp = frame.timestamp;
  sample.map_position = frame.map_position;
  sample.enu = enu_frame.ToEnu(fixes[fix_index].position);
  sample.sigma_m = fixes[fix_index].sigma_m;
  sample.fix_index = fix_index;
  sample.camera_down = frame.camera_down;
  return sample;
}

std::optional<Sim3d> Fit(const Points3d& src, const Points3d& tgt, const std::vector<double>& weights,
                         bool estimate_scale) {
  if (estimate_scale) return AlignSim3(src, tgt, weights);
  const auto rigid = AlignRigid3(src, tgt, weights);
  if (!rigid) return std::nullopt;
  return Sim3d(*rigid);
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  return values[mid];
}

// Smallest sine of the triangle's angles (0 for degenerate triangles).
double TriangleSine(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, bc = c - b;
  const double area2 = ab.cross(ac).norm();
  const double lab = ab.norm(), lac = ac.norm(), lbc = bc.norm();
  const double longest = std::max({lab, lac, lbc});
  if (longest <= 0) return 0.0;
  // sin(angle) = 2*area / (product of the two adjacent sides); the smallest angle is opposite the shortest
  // side, between the two longer ones.
  const double shortest = std::min({lab, lac, lbc});
  const double middle = lab + lac + lbc - longest - shortest;
  return middle > 0 ? area2 / (longest * middle) : 0.0;
}

// Sum of weight * (p - mean)(p - mean)^T over the points (unit weights when `weights` is empty).
Eigen::Matrix3d Scatter(const Points3d& points, const std::vector<double>& weights,
                        const Eigen::Vector3d& mean) {
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < points.size(); ++i)
    scatter += (weights.empty() ? 1.0 : weights[i]) * (points[i] - mean) * (points[i] - mean).transpose();
  return scatter;
}

// Eigenvalues (ascending) of the points' scatter about their mean, per point.
Eigen::Vector3d ScatterEigenvalues(const Points3d& points) {
  if (points.size() < 2) return Eigen::Vector3d::Zero();
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(
      Scatter(points, {}, mean) / static_cast<double>(points.size()), Eigen::EigenvaluesOnly);
  return solver.eigenvalues().cwiseMax(0.0);
}

// sqrt(second / largest) of a scatter's eigenvalues (ascending): 0 on a line, 1 for an isotropic spread.
double SpreadRatio(const Eigen::Vector3d& eigenvalues) {
  return eigenvalues(2) > 0 ? std::sqrt(eigenvalues(1) / eigenvalues(2)) : 0.0;
}

// RMS distance of the map positions from their principal line, in the fixes' metres (the scale from the
// spreads along the lines: the map's own for a metric map), from the two scatters' eigenvalues.
double AcrossLineSpreadMetres(const Eigen::Vector3d& map_eigenvalues, const Eigen::Vector3d& enu_eigenvalues,
                              bool estimate_scale) {
  const double scale = !estimate_scale          ? 1.0
                       : map_eigenvalues(2) > 0 ? std::sqrt(enu_eigenvalues(2) / map_eigenvalues(2))
                                                : 0.0;
  return scale * std::sqrt(map_eigenvalues(0) + map_eigenvalues(1));
}

// Unit principal axis of the weighted points' scatter around `mean`.
Eigen::Vector3d PrincipalAxis(const Points3d& points, const std::vector<double>& weights,
                              const Eigen::Vector3d& mean) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(Scatter(points, weights, mean));
  return solver.eigenvectors().col(2);
}

// A right-handed frame whose first axis is `along` and whose second is `down` off it; nullopt when `down`
// lies (nearly) along `along`.
std::optional<Eigen::Matrix3d> LineFrame(const Eigen::Vector3d& along, const Eigen::Vector3d& down) {
  constexpr double kMinSine = 0.3;  // down at least ~17 degrees off the line
  const Eigen::Vector3d off = down - down.dot(along) * along;
  if (!(off.norm() > kMinSine * down.norm())) return std::nullopt;
  Eigen::Matrix3d frame;
  frame.col(0) = along;
  frame.col(1) = off.normalized();
  frame.col(2) = along.cross(frame.col(1));
  return frame;
}

// The similarity that lays the map positions' line onto the fixes' line (weighted least squares along it),
// turned about it so that `map_down` comes nearest to the world's down (ENU: -z). Points on a line fix all
// but that roll.
std::optional<Sim3d> FitAlongLine(const Points3d& src, const Points3d& tgt, std::vector<double> weights,
                                  const Eigen::Vector3d& map_down, bool estimate_scale) {
  if (weights.empty()) weights.assign(src.size(), 1.0);
  double total = 0.0;
  Eigen::Vector3d src_mean = Eigen::Vector3d::Zero(), tgt_mean = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    total += weights[i];
    src_mean += weights[i] * src[i];
    tgt_mean += weights[i] * tgt[i];
  }
  if (!(total > 0)) return std::nullopt;
  src_mean /= total;
  tgt_mean /= total;
  const Eigen::Vector3d src_axis = PrincipalAxis(src, weights, src_mean);
  Eigen::Vector3d tgt_axis = PrincipalAxis(tgt, weights, tgt_mean);
  double cross = 0.0, src_var = 0.0;
  for (size_t i = 0; i < src.size(); ++i) {
    const double a = (src[i] - src_mean).dot(src_axis);
    cross += weights[i] * a * (tgt[i] - tgt_mean).dot(tgt_axis);
    src_var += weights[i] * a * a;
  }
  if (cross < 0) {
    tgt_axis = -tgt_axis;
    cross = -cross;
  }
  if (!(src_var > 0) || !(cross > 0)) return std::nullopt;
  const auto src_frame = LineFrame(src_axis, map_down);
  const auto tgt_frame = LineFrame(tgt_axis, -Eigen::Vector3d::UnitZ());
  if (!src_frame || !tgt_frame) return std::nullopt;
  const Eigen::Matrix3d rotation = *tgt_frame * src_frame->transpose();
  const double scale = estimate_scale ? cross / src_var : 1.0;
  return Sim3d(scale, Eigen::Quaterniond(rotation), tgt_mean - scale * (rotation * src_mean));
}

// The samples' mean camera down axis (zero when they carry none).
Eigen::Vector3d MeanCameraDown(const std::vector<GpsSample>& samples) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const GpsSample& s : samples) sum += s.camera_down;
  return samples.empty() ? sum : sum / static_cast<double>(samples.size());
}

}  // namespace

std::vector<GpsSample> SampleGpsPairs(const std::vector<FramePosition>& frames,
                                      const std::vector<GpsFix>& fixes, const EnuFrame& enu_frame,
                                      const GpsSamplingOptions& options) {
  GpsSampler sampler(fixes, enu_frame, options);
  std::vector<GpsSample> samples;
  for (const FramePosition& frame : frames) {
    if (auto sample = sampler.AddFrame(frame)) samples.push_back(*sample);
  }
  return samples;
}

GpsSampler::GpsSampler(std::vector<GpsFix> fixes, EnuFrame enu_frame, GpsSamplingOptions options)
    : fixes_(std::move(fixes)), enu_frame_(std::move(enu_frame)), options_(options) {
  options_.Check();
}

std::optional<GpsSample> GpsSampler::AddFrame(const FramePosition& frame) {
  if (next_frame_ && frame.frame_index < *next_frame_) return std::nullopt;
  if (!frame.map_position.allFinite()) return std::nullopt;
  const auto match =
      MatchFixesToTimes(fixes_, {frame.timestamp}, options_.match_tolerance_s, options_.time_offset_s)[0];
  if (!match) return std::nullopt;  // no fix here (dropout): try the next frame
  // The next sample at the next multiple of N after this frame's slot.
  const size_t n = static_cast<size_t>(options_.every_n_frames);
  next_frame_ = (frame.frame_index / n + 1) * n;
  return MakeSample(frame, fixes_, *match, enu_frame_);
}

std::optional<Sim3d> AlignAlongLine(const Points3d& map, const Points3d& enu, const Eigen::Vector3d& map_down,
                                    bool estimate_scale) {
  Require(map.size() == enu.size(), "AlignAlongLine: map and ENU positions differ in number");
  if (map.size() < 2) return std::nullopt;
  return FitAlongLine(map, enu, {}, map_down, estimate_scale);
}

GpsAlignment EvaluateAlignment(const Sim3d& enu_from_map, const std::vector<GpsSample>& samples,
                               const GpsAlignmentOptions& options) {
  GpsAlignment result;
  result.enu_from_map = enu_from_map;
  result.residuals_m.resize(samples.size());
  for (size_t i = 0; i < samples.size(); ++i) {
    result.residuals_m[i] = (samples[i].enu - enu_from_map * samples[i].map_position).norm();
  }
  const double spread = options.inlier_mad_factor * Median(result.residuals_m);
  result.inliers.resize(samples.size());
  double inlier_sum = 0.0, all_sum = 0.0;
  for (size_t i = 0; i < samples.size(); ++i) {
    const double threshold =
        std::max({options.inlier_threshold_m, options.inlier_sigma_factor * samples[i].sigma_m, spread});
    const double r = result.residuals_m[i];
    result.inliers[i] = r < threshold;
    all_sum += r * r;
    if (result.inliers[i]) {
      ++result.num_inliers;
      inlier_sum += r * r;
    }
  }
  if (!samples.empty()) result.rmse_m = std::sqrt(all_sum / static_cast<double>(samples.size()));
  if (result.num_inliers > 0) result.inlier_rmse_m = std::sqrt(inlier_sum / result.num_inliers);
  return result;
}

std::optional<GpsAlignment> AlignMapToGps(const std::vector<GpsSample>& samples,
                                          const GpsAlignmentOptions& options) {
  options.Check();
  const size_t n = samples.size();
  if (n < static_cast<size_t>(options.min_samples)) return std::nullopt;
  Points3d src(n), tgt(n);
  std::vector<double> base_weight(n);
  for (size_t i = 0; i < n; ++i) {
    src[i] = samples[i].map_position;
    tgt[i] = samples[i].enu;
    base_weight[i] = 1.0 / (samples[i].sigma_m * samples[i].sigma_m);
  }

  // Nearly collinear map positions leave the roll about their line undetermined (a straight drive with a
  // gentle grade is not "exactly" collinear, so Umeyama alone would return an arbitrary roll); the cameras'
  // down axis, where the samples carry it, sets that roll.
  const Eigen::Vector3d map_down = MeanCameraDown(samples);
  // Unit axes that agree give a mean near unit length; a mean of axes pointing every way is no axis.
  constexpr double kMinDownAgreement = 0.5;
  const bool down_known = options.roll_from_camera_down && map_down.norm() > kMinDownAgreement;
  const Eigen::Vector3d map_spread = ScatterEigenvalues(src);
  bool along_line = SpreadRatio(map_spread) < options.min_spread_ratio;
  if (along_line && !down_known) return std::nullopt;
  if (!along_line && down_known) {
    std::vector<double> sigmas;
    for (const GpsSample& s : samples) sigmas.push_back(s.sigma_m);
    along_line = AcrossLineSpreadMetres(map_spread, ScatterEigenvalues(tgt), options.estimate_scale) <
                 options.min_roll_spread_sigmas * Median(sigmas);
  }
  const auto fit = [&](const Points3d& s, const Points3d& t, const std::vector<double>& w) {
    return along_line ? FitAlongLine(s, t, w, map_down, options.estimate_scale)
                      : Fit(s, t, w, options.estimate_scale);
  };

  // RANSAC (MSAC scoring) over minimal sets: triples, or pairs along a line.
  std::optional<Sim3d> best;
  const auto ransac = [&] {
    double best_cost = std::numeric_limits<double>::infinity();
    std::mt19937_64 rng(options.seed);
    std::uniform_int_distribution<size_t> pick(0, n - 1);
    for (int iteration = 0; iteration < options.ransac_iterations; ++iteration) {
      // Along a line a pair is minimal: no third draw (c stands in for a).
      const size_t a = pick(rng), b = pick(rng), c = along_line ? a : pick(rng);
      if (a == b || (!along_line && (a == c || b == c))) continue;
      if (!along_line && (TriangleSine(src[a], src[b], src[c]) < options.min_triangle_sine ||
                          TriangleSine(tgt[a], tgt[b], tgt[c]) < options.min_triangle_sine)) {
        continue;
      }
      const auto model = along_line ? fit({src[a], src[b]}, {tgt[a], tgt[b]}, {})
                                    : fit({src[a], src[b], src[c]}, {tgt[a], tgt[b], tgt[c]}, {});
      if (!model) continue;
      double cost = 0.0;
      for (size_t i = 0; i < n; ++i) {
        const double threshold =
            std::max(options.inlier_threshold_m, options.inlier_sigma_factor * samples[i].sigma_m);
        cost += std::min((tgt[i] - *model * src[i]).squaredNorm(), threshold * threshold);
      }
      if (cost < best_cost) {
        best_cost = cost;
        best = model;
      }
    }
  };
  if (options.ransac_iterations > 0) {
    ransac();
    // Every minimal triple degenerate: the positions lie nearly on one line (a straight drive so far).
    if (!best && !along_line && down_known) {
      along_line = true;
      ransac();
    }
    if (!best) return std::nullopt;
  }
  if (!best) best = fit(src, tgt, base_weight);
  if (!best) return std::nullopt;

  // Refit on the inliers, then reweight (Cauchy) and re-select until the inlier set settles.
  GpsAlignment current = EvaluateAlignment(*best, samples, options);
  for (int iteration = 0; iteration <= options.irls_iterations; ++iteration) {
    std::vector<double> weights(n, 0.0);
    for (size_t i = 0; i < n; ++i) {
      if (!current.inliers[i]) continue;
      const double u = current.residuals_m[i] / (options.cauchy_scale * samples[i].sigma_m);
      weights[i] = base_weight[i] * (iteration == 0 ? 1.0 : 1.0 / (1.0 + u * u));
    }
    const auto refit = fit(src, tgt, weights);
    if (!refit) break;
    GpsAlignment next = EvaluateAlignment(*refit, samples, options);
    const bool settled = next.inliers == current.inliers &&
                         (next.enu_from_map.translation - current.enu_from_map.translation).norm() < 1e-6 &&
                         std::abs(next.enu_from_map.scale / current.enu_from_map.scale - 1.0) < 1e-9;
    current = std::move(next);
    if (settled && iteration > 0) break;
  }
  if (current.num_inliers < 3) return std::nullopt;
  current.roll_from_camera_down = along_line;
  return current;
}

IncrementalGpsAligner::IncrementalGpsAligner(GpsAlignmentOptions options) : options_(options) {
  options_.Check();
}

const std::optional<GpsAlignment>& IncrementalGpsAligner::Add(const GpsSample& sample) {
  samples_.push_back(sample);
  Reestimate();
  return current_;
}

const std::optional<GpsAlignment>& IncrementalGpsAligner::UpdateMapPositions(
    const std::function<std::optional<Eigen::Vector3d>(size_t frame_index)>& position_of) {
  for (GpsSample& sample : samples_) {
    if (const auto position = position_of(sample.frame_index)) sample.map_position = *position;
  }
  Reestimate();
  return current_;
}

void IncrementalGpsAligner::Reestimate() {
  auto estimate = AlignMapToGps(samples_, options_);
  if (estimate) {
    current_ = std::move(estimate);
  } else if (current_) {
    // Degenerate for now (cannot happen by adding samples to a good set, but moved positions can): keep the
    // last transform, with residuals for every sample.
    current_ = EvaluateAlignment(current_->enu_from_map, samples_, options_);
  }
}

}  // namespace semslam
