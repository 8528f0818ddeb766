#pragma once
// Two-view relations between matched image points (Hartley & Zisserman, "Multiple View Geometry", 2nd ed.):
// the homography of a plane and the fundamental matrix, estimated linearly from normalized coordinates, and
// their decompositions into the camera motion. Points are in any consistent frame (undistorted pixels or
// normalized image coordinates); the motion is `camera2_from_camera1`: X2 = R X1 + t.

#include <optional>
#include <vector>

#include "semslam/geometry/rigid3.h"

namespace semslam {

// The similarity T (isotropic scaling and shift) that moves `points` to centroid 0 and mean distance sqrt(2)
// from it (Hartley 1997). Identity for an empty or coincident set.
Eigen::Matrix3d HartleyNormalization(const Points2d& points);

// x2 ~ H x1 from >= 4 pairs (normalized DLT, H&Z Alg. 4.2), scaled to unit Frobenius norm. nullopt for fewer
// than 4 pairs, mismatched sizes or a degenerate configuration (three of four points collinear).
std::optional<Eigen::Matrix3d> EstimateHomography(const Points2d& x1, const Points2d& x2);

// x2^T F x1 = 0 from >= 8 pairs (normalized eight-point algorithm, H&Z Alg. 11.1), rank 2 enforced, unit
// Frobenius norm. nullopt for fewer than 8 pairs, mismatched sizes or a degenerate configuration.
std::optional<Eigen::Matrix3d> EstimateFundamental(const Points2d& x1, const Points2d& x2);

// One motion hypothesis of a plane-induced homography in normalized coordinates.
struct HomographyMotion {
  // Translation in units of the plane's distance from camera 1 (t / d); zero for a pure rotation.
  Rigid3d camera2_from_camera1;
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // plane normal in camera 1: n^T X1 = d
};

// The 8 hypotheses (R, t/d, n) with H ~ R + (t/d) n^T (Faugeras & Lustman 1988): two signs of the plane
// distance times four sign choices of the normal; the physically valid one is found by triangulation.
// `h` maps normalized coordinates (K^-1 H K for a pixel homography). A homography with three equal singular
// values (a pure rotation, or a plane at infinity) gives the single hypothesis (R, 0).
std::vector<HomographyMotion> DecomposeHomography(const Eigen::Matrix3d& h);

// The 4 hypotheses (R, t) of an essential matrix E = [t]x R, |t| = 1 (H&Z §9.6.2).
std::vector<Rigid3d> DecomposeEssential(const Eigen::Matrix3d& e);

// Levenberg-Marquardt on the Sampson error of E = [t]x R over the pairs with use[i] (all when `use` is
// empty), in normalized coordinates, from `camera2_from_camera1` (|t| = 1 is kept: 5 degrees of freedom). The
// linear eight-point estimate minimizes an algebraic error, biased for small baselines; this is the geometric
// one to first order. Returns the start when fewer than 5 pairs are used.
Rigid3d RefineRelativePose(const Rigid3d& camera2_from_camera1, const Points2d& x1, const Points2d& x2,
                           const std::vector<bool>& use = {}, int max_iterations = 10);

// The Sampson approximation of the geometric distance (sum over both images) of a pair to x2^T F x1 = 0,
// signed; its square is the first-order squared reprojection error.
double SampsonError(const Eigen::Matrix3d& f, const Eigen::Vector2d& x1, const Eigen::Vector2d& x2);

}  // namespace semslam
