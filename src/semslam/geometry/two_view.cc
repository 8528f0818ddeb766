#include "semslam/geometry/two_view.h"

#include <fmt/format.h>

#include <algorithm>
#include <functional>
#include <array>
#include <cmath>
#include <future>
#include <limits>
#include <numbers>
#include <system_error>

#include "semslam/core/error.h"
#include "semslam/geometry/epipolar.h"
#include "semslam/geometry/ransac.h"

namespace semslam {

void TwoViewOptions::Check() const {
  Require(max_iterations >= 1, "two-view: max_iterations must be >= 1");
  Require(std::isfinite(sigma_px) && sigma_px > 0, "two-view: sigma_px must be positive");
  Require(std::isfinite(chi2_homography) && chi2_homography > 0,
          "two-view: chi2_homography must be positive");
  Require(std::isfinite(chi2_fundamental) && chi2_fundamental > 0,
          "two-view: chi2_fundamental must be positive");
  Require(std::isfinite(score_threshold) && score_threshold >= std::max(chi2_homography, chi2_fundamental),
          "two-view: score_threshold must be >= both chi-square thresholds");
  Require(refine_iterations >= 0, "two-view: refine_iterations must be >= 0");
  Require(homography_ratio >= 0 && homography_ratio <= 1, "two-view: homography_ratio must be in [0, 1]");
  Require(std::isfinite(reprojection_sigmas) && reprojection_sigmas > 0,
          "two-view: reprojection_sigmas must be positive");
  Require(min_point_parallax_deg >= 0 && min_point_parallax_deg < 90,
          "two-view: min_point_parallax_deg must be in [0, 90)");
  Require(min_parallax_deg >= 0 && min_parallax_deg < 90, "two-view: min_parallax_deg must be in [0, 90)");
  Require(parallax_rank >= 1, "two-view: parallax_rank must be >= 1");
  Require(parallax_grid_cols >= 1 && parallax_grid_rows >= 1,
          "two-view: the parallax grid needs a cell at least");
  Require(parallax_cell_share > 0 && parallax_cell_share <= 1,
          "two-view: parallax_cell_share must be in (0, 1]");
  Require(min_good_points >= 1, "two-view: min_good_points must be >= 1");
  Require(min_good_ratio >= 0 && min_good_ratio <= 1, "two-view: min_good_ratio must be in [0, 1]");
  Require(ambiguity_ratio > 0 && ambiguity_ratio <= 1, "two-view: ambiguity_ratio must be in (0, 1]");
}

namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
using SampleSet = std::array<size_t, 8>;

struct ModelFit {
  bool valid = false;
  Eigen::Matrix3d matrix = Eigen::Matrix3d::Zero();  // H21 (x2 ~ H x1) or F21 (x2^T F x1 = 0)
  double score = 0.0;
  std::vector<bool> inliers;
  int num_inliers = 0;
};

// ORB-SLAM's score: each image whose chi2 = (error / sigma)^2 is under `chi2_threshold` adds
// score_threshold - chi2; a match is an inlier when both images are under it. Written on scalars: this loop
// is most of the time of the initialization.
double ScoreHomography(const Eigen::Matrix3d& h21, const Points2d& x1, const Points2d& x2,
                       const TwoViewOptions& options, std::vector<bool>* inliers) {
  const Eigen::Matrix3d h12 = h21.inverse();
  const double inv_sigma2 = 1.0 / (options.sigma_px * options.sigma_px);
  const double threshold = options.chi2_homography;
  const double score_threshold = options.score_threshold;
  // chi2 of `x` against H applied to `y`; infinite when H y is at infinity.
  const auto transfer_chi2 = [inv_sigma2](const Eigen::Matrix3d& h, const Eigen::Vector2d& y,
                                          const Eigen::Vector2d& x) {
    const double w = h(2, 0) * y.x() + h(2, 1) * y.y() + h(2, 2);
    if (!(std::abs(w) > 1e-12)) return std::numeric_limits<double>::infinity();
    const double inv_w = 1.0 / w;
    const double du = (h(0, 0) * y.x() + h(0, 1) * y.y() + h(0, 2)) * inv_w - x.x();
    const double dv = (h(1, 0) * y.x() + h(1, 1) * y.y() + h(1, 2)) * inv_w - x.y();
    return (du * du + dv * dv) * inv_sigma2;
  };
  double score = 0.0;
  for (size_t i = 0; i < x1.size(); ++i) {
    const double chi2_in2 = transfer_chi2(h21, x1[i], x2[i]);
    const double chi2_in1 = transfer_chi2(h12, x2[i], x1[i]);
    const bool in2 = chi2_in2 < threshold;
    const bool in1 = chi2_in1 < threshold;
    if (in2) score += score_threshold - chi2_in2;
    if (in1) score += score_threshold - chi2_in1;
    if (inliers != nullptr) (*inliers)[i] = in1 && in2;
  }
  return score;
}

double ScoreFundamental(const Eigen::Matrix3d& f21, const Points2d& x1, const Points2d& x2,
                        const TwoViewOptions& options, std::vector<bool>* inliers) {
  const double inv_sigma2 = 1.0 / (options.sigma_px * options.sigma_px);
  const double threshold = options.chi2_fundamental;
  const double score_threshold = options.score_threshold;
  const Eigen::Matrix3d& f = f21;
  double score = 0.0;
  for (size_t i = 0; i < x1.size(); ++i) {
    const double u1 = x1[i].x(), v1 = x1[i].y(), u2 = x2[i].x(), v2 = x2[i].y();
    // Epipolar line of x1 in image 2 (a2, b2, c2) and of x2 in image 1 (a1, b1, c1).
    const double a2 = f(0, 0) * u1 + f(0, 1) * v1 + f(0, 2);
    const double b2 = f(1, 0) * u1 + f(1, 1) * v1 + f(1, 2);
    const double c2 = f(2, 0) * u1 + f(2, 1) * v1 + f(2, 2);
    const double a1 = f(0, 0) * u2 + f(1, 0) * v2 + f(2, 0);
    const double b1 = f(0, 1) * u2 + f(1, 1) * v2 + f(2, 1);
    const double residual = a2 * u2 + b2 * v2 + c2;  // x2^T F x1
    const double residual2 = residual * residual * inv_sigma2;
    const double norm2 = a2 * a2 + b2 * b2;
    const double norm1 = a1 * a1 + b1 * b1;
    // chi2 < threshold  <=>  residual2 < threshold * norm (no division, and a zero norm is never an inlier).
    const bool in2 = residual2 < threshold * norm2;
    const bool in1 = residual2 < threshold * norm1;
    if (in2) score += score_threshold - residual2 / norm2;
    if (in1) score += score_threshold - residual2 / norm1;
    if (inliers != nullptr) (*inliers)[i] = in1 && in2;
  }
  return score;
}

enum class Model { kHomography, kFundamental };

// RANSAC over the shared sample sets (H from the first 4 matches of each set, F from all 8), then
// least-squares refits on the inliers while they raise the score.
ModelFit FitModel(Model model, const Points2d& x1, const Points2d& x2, const std::vector<SampleSet>& sets,
                  const TwoViewOptions& options) {
  const size_t sample_size = model == Model::kHomography ? 4 : 8;
  const auto estimate = [&](const Points2d& a, const Points2d& b) {
    return model == Model::kHomography ? EstimateHomography(a, b) : EstimateFundamental(a, b);
  };
  const auto score = [&](const Eigen::Matrix3d& m, std::vector<bool>* inliers) {
    return model == Model::kHomography ? ScoreHomography(m, x1, x2, options, inliers)
                                       : ScoreFundamental(m, x1, x2, options, inliers);
  };
  ModelFit best;
  Points2d sample1(sample_size), sample2(sample_size);
  for (const SampleSet& set : sets) {
    for (size_t k = 0; k < sample_size; ++k) {
      sample1[k] = x1[set[k]];
      sample2[k] = x2[set[k]];
    }
    const auto m = estimate(sample1, sample2);
    if (!m) continue;
    const double s = score(*m, nullptr);
    if (!best.valid || s > best.score) {
      best.valid = true;
      best.matrix = *m;
      best.score = s;
    }
  }
  if (!best.valid) return best;
  best.inliers.assign(x1.size(), false);
  score(best.matrix, &best.inliers);
  for (int round = 0; round < 3; ++round) {
    Points2d in1, in2;
    for (size_t i = 0; i < x1.size(); ++i) {
      if (!best.inliers[i]) continue;
      in1.push_back(x1[i]);
      in2.push_back(x2[i]);
    }
    const auto m = estimate(in1, in2);
    if (!m) break;
    std::vector<bool> inliers(x1.size(), false);
    const double s = score(*m, &inliers);
    if (!(s > best.score)) break;
    best.matrix = *m;
    best.score = s;
    best.inliers = std::move(inliers);
  }
  best.num_inliers = static_cast<int>(std::count(best.inliers.begin(), best.inliers.end(), true));
  return best;
}

// A motion hypothesis and the matches it explains.
struct Hypothesis {
  Rigid3d camera2_from_camera1;
  int good = 0;
  double parallax_deg = 0.0;  // the options' quantile over the good matches
  std::vector<bool> triangulated;
  Points3d points;
};

// The cell of the parallax ranking's grid (TwoViewOptions::parallax_grid_cols/rows) an ideal pixel falls in.
int ParallaxCell(const Eigen::Vector2d& pixel, const PinholeCamera& camera, const TwoViewOptions& options) {
  const int col = std::clamp(static_cast<int>(pixel.x() * options.parallax_grid_cols / camera.width), 0,
                             options.parallax_grid_cols - 1);
  const int row = std::clamp(static_cast<int>(pixel.y() * options.parallax_grid_rows / camera.height), 0,
                             options.parallax_grid_rows - 1);
  return row * options.parallax_grid_cols + col;
}

// Triangulates every inlier under camera2_from_camera1 (|t| = 1, or 0 for a pure rotation) and counts the
// matches it explains: reprojection within the threshold in both images, in front of both cameras when the
// parallax is enough to tell; a match with too little parallax to triangulate is explained by the rotation
// alone when its point at infinity transfers within the threshold.
// `cells1[i]`: match i's ParallaxCell in image 1.
Hypothesis CheckMotion(const Rigid3d& camera2_from_camera1, const Points2d& n1, const Points2d& n2,
                       const std::vector<int>& cells1, const std::vector<bool>& inliers,
                       const PinholeCamera& camera, const TwoViewOptions& options) {
  Hypothesis h;
  h.camera2_from_camera1 = camera2_from_camera1;
  h.triangulated.assign(n1.size(), false);
  h.points.assign(n1.size(), Eigen::Vector3d::Zero());
  const Eigen::Matrix3d r = camera2_from_camera1.rotation.toRotationMatrix();
  const Eigen::Vector3d& t = camera2_from_camera1.translation;
  const double max_error2 = std::pow(options.reprojection_sigmas * options.sigma_px, 2);
  const double cos_min_point_parallax = std::cos(options.min_point_parallax_deg * kDegree);
  const auto pixel_error2 = [&](const Eigen::Vector3d& p, const Eigen::Vector2d& n) {
    if (!(std::abs(p.z()) > 1e-12)) return std::numeric_limits<double>::infinity();
    const double du = camera.fx * (p.x() / p.z() - n.x());
    const double dv = camera.fy * (p.y() / p.z() - n.y());
    return du * du + dv * dv;
  };
  struct RankedPoint {
    double parallax_deg;
    int cell;
  };
  std::vector<RankedPoint> parallaxes;
  for (size_t i = 0; i < n1.size(); ++i) {
    if (!inliers[i]) continue;
    const Eigen::Vector3d b1 = n1[i].homogeneous();
    const Eigen::Vector3d b2 = n2[i].homogeneous();
    const double cos_parallax = std::clamp(b1.normalized().dot(r.transpose() * b2.normalized()), -1.0, 1.0);
    const bool low_parallax = cos_parallax > cos_min_point_parallax;

    // Linear triangulation in camera 1 (inhomogeneous DLT): x1 Z - X = 0, y1 Z - Y = 0 and
    // (x2 r3 - r1) . X = t1 - x2 t3, (y2 r3 - r2) . X = t2 - y2 t3.
    Eigen::Matrix<double, 4, 3> a;
    Eigen::Vector4d rhs;
    a.row(0) << -1, 0, n1[i].x();
    a.row(1) << 0, -1, n1[i].y();
    a.row(2) = n2[i].x() * r.row(2) - r.row(0);
    a.row(3) = n2[i].y() * r.row(2) - r.row(1);
    rhs << 0, 0, t.x() - n2[i].x() * t.z(), t.y() - n2[i].y() * t.z();
    const Eigen::Matrix3d ata = a.transpose() * a;
    bool good = false;
    if (std::abs(ata.determinant()) > 1e-18) {
      const Eigen::Vector3d x = ata.ldlt().solve(a.transpose() * rhs);
      const Eigen::Vector3d x2 = r * x + t;
      if (x.allFinite() && (low_parallax || (x.z() > 0 && x2.z() > 0)) &&
          pixel_error2(x, n1[i]) < max_error2 && pixel_error2(x2, n2[i]) < max_error2) {
        good = true;
        if (!low_parallax) {
          h.triangulated[i] = true;
          h.points[i] = x;
        }
      }
    }
    if (!good && low_parallax) {
      good = pixel_error2(r * b1, n2[i]) < max_error2 && pixel_error2(r.transpose() * b2, n1[i]) < max_error2;
    }
    if (!good) continue;
    ++h.good;
    parallaxes.push_back({std::acos(cos_parallax) / kDegree, cells1[i]});
  }
  // Largest first (ties by cell, so the order is the same on every machine), each cell up to its cap.
  std::sort(parallaxes.begin(), parallaxes.end(), [](const RankedPoint& a, const RankedPoint& b) {
    return a.parallax_deg != b.parallax_deg ? a.parallax_deg > b.parallax_deg : a.cell < b.cell;
  });
  const int cap = static_cast<int>(std::ceil(options.parallax_cell_share * options.parallax_rank));
  std::vector<int> per_cell(static_cast<size_t>(options.parallax_grid_cols * options.parallax_grid_rows), 0);
  int ranked = 0;
  for (const RankedPoint& p : parallaxes) {
    if (per_cell[static_cast<size_t>(p.cell)]++ >= cap) continue;
    h.parallax_deg = p.parallax_deg;  // the least counted so far
    if (++ranked == options.parallax_rank) break;
  }
  return h;
}

}  // namespace

TwoViewResult InitializeTwoView(const std::vector<Eigen::Vector2d>& pixels1,
                                const std::vector<Eigen::Vector2d>& pixels2, const PinholeCamera& camera,
                                const TwoViewOptions& options) {
  options.Check();
  camera.Check();
  Require(pixels1.size() == pixels2.size(),
          fmt::format("two-view: {} pixels in image 1 but {} in image 2", pixels1.size(), pixels2.size()));
  const size_t n = pixels1.size();
  for (size_t i = 0; i < n; ++i) {
    Require(pixels1[i].allFinite() && pixels2[i].allFinite(),
            fmt::format("two-view: match {} is not finite", i));
  }

  TwoViewResult result;
  result.points.assign(n, Eigen::Vector3d::Zero());
  result.triangulated.assign(n, false);
  if (n < 8) {
    result.reason = fmt::format("too few matches ({} < 8)", n);
    return result;
  }

  // Undistorted: normalized coordinates for the geometry, ideal pixels (K n) for the errors.
  Points2d normalized1(n), normalized2(n), ideal1(n), ideal2(n);
  std::vector<int> cells1(n);
  const auto ideal = [&](const Eigen::Vector2d& m) {
    return Eigen::Vector2d(camera.fx * m.x() + camera.cx, camera.fy * m.y() + camera.cy);
  };
  for (size_t i = 0; i < n; ++i) {
    normalized1[i] = camera.PixelToNormalized(pixels1[i]);
    normalized2[i] = camera.PixelToNormalized(pixels2[i]);
    ideal1[i] = ideal(normalized1[i]);
    ideal2[i] = ideal(normalized2[i]);
    cells1[i] = ParallaxCell(ideal1[i], camera, options);
  }

  RansacSampler sampler(options.seed);
  std::vector<SampleSet> sets(static_cast<size_t>(options.max_iterations));
  std::vector<size_t> draw;
  for (SampleSet& set : sets) {
    sampler.Sample(n, 8, draw);
    std::copy(draw.begin(), draw.end(), set.begin());
  }
  ModelFit homography, fundamental;
  std::future<ModelFit> fundamental_future;
  if (options.parallel) {
    try {
      fundamental_future = std::async(
          std::launch::async, [&] { return FitModel(Model::kFundamental, ideal1, ideal2, sets, options); });
    } catch (const std::system_error&) {
      // No thread available: the same work, in sequence.
    }
  }
  if (fundamental_future.valid()) {
    homography = FitModel(Model::kHomography, ideal1, ideal2, sets, options);
    fundamental = fundamental_future.get();
  } else {
    homography = FitModel(Model::kHomography, ideal1, ideal2, sets, options);
    fundamental = FitModel(Model::kFundamental, ideal1, ideal2, sets, options);
  }
  result.homography_score = homography.score;
  result.fundamental_score = fundamental.score;
  result.homography_inliers = homography.num_inliers;
  result.fundamental_inliers = fundamental.num_inliers;
  const double total = homography.score + fundamental.score;
  if (!(total > 0)) {
    result.reason = "no homography or fundamental matrix fits (degenerate matches)";
    return result;
  }
  result.score_ratio = homography.score / total;
  const bool use_homography = result.score_ratio > options.homography_ratio;
  ModelFit& fit = use_homography ? homography : fundamental;
  result.model = use_homography ? "homography" : "fundamental";
  result.num_inliers = fit.num_inliers;
  if (fit.num_inliers < options.min_good_points) {
    result.reason = fmt::format("too few inliers ({} of {} matches, {} needed)", fit.num_inliers, n,
                                options.min_good_points);
    return result;
  }

  // Motion hypotheses, translation of unit length.
  std::vector<Rigid3d> motions;
  const Eigen::Matrix3d k = camera.K();
  if (use_homography) {
    for (const HomographyMotion& m : DecomposeHomography(k.inverse() * fit.matrix * k))
      motions.push_back(m.camera2_from_camera1);
  } else {
    motions = DecomposeEssential(k.transpose() * fit.matrix * k);
    if (!motions.empty() && options.refine_iterations > 0) {
      // The Sampson error of E = [t]x R does not tell the four hypotheses apart: refine any, then decompose.
      const Eigen::Matrix3d k_inv = k.inverse();
      Rigid3d motion = motions.front();
      for (int round = 0; round < 2; ++round) {
        motion = RefineRelativePose(motion, normalized1, normalized2, fit.inliers, options.refine_iterations);
        const Eigen::Matrix3d f = k_inv.transpose() * SkewSymmetric(motion.translation) *
                                  motion.rotation.toRotationMatrix() * k_inv;
        fit.score = ScoreFundamental(f, ideal1, ideal2, options, &fit.inliers);
        fit.matrix = f;
      }
      fit.num_inliers = static_cast<int>(std::count(fit.inliers.begin(), fit.inliers.end(), true));
      result.num_inliers = fit.num_inliers;
      motions = DecomposeEssential(SkewSymmetric(motion.translation) * motion.rotation.toRotationMatrix());
    }
  }
  for (Rigid3d& m : motions) {
    const double norm = m.translation.norm();
    if (norm > 1e-12) m.translation /= norm;
  }
  if (motions.empty()) {
    result.reason = fmt::format("the {} has no motion decomposition", result.model);
    return result;
  }
  std::vector<Hypothesis> hypotheses;
  for (const Rigid3d& m : motions)
    hypotheses.push_back(CheckMotion(m, normalized1, normalized2, cells1, fit.inliers, camera, options));
  std::sort(hypotheses.begin(), hypotheses.end(),
            [](const Hypothesis& a, const Hypothesis& b) { return a.good > b.good; });
  Hypothesis& best = hypotheses.front();
  result.num_good = best.good;
  result.second_best_good = hypotheses.size() > 1 ? hypotheses[1].good : 0;
  result.parallax_deg = best.parallax_deg;

  if (best.good == 0) {
    result.reason = fmt::format("no motion hypothesis of the {} explains its inliers", result.model);
    return result;
  }
  if (best.parallax_deg < options.min_parallax_deg) {
    result.reason =
        fmt::format("low parallax ({:.2f} deg < {:.2f} deg)", best.parallax_deg, options.min_parallax_deg);
    return result;
  }
  if (result.second_best_good > options.ambiguity_ratio * best.good) {
    result.reason = fmt::format("ambiguous: two motion hypotheses explain {} and {} matches", best.good,
                                result.second_best_good);
    return result;
  }
  const int needed = std::max(options.min_good_points,
                              static_cast<int>(std::ceil(options.min_good_ratio * fit.num_inliers)));
  if (best.good < needed) {
    result.reason =
        fmt::format("too few good points ({} of {} inliers, {} needed)", best.good, fit.num_inliers, needed);
    return result;
  }
  result.success = true;
  result.camera2_from_camera1 = best.camera2_from_camera1;
  result.points = std::move(best.points);
  result.triangulated = std::move(best.triangulated);
  return result;
}

}  // namespace semslam
