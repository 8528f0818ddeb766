#include "semslam/geometry/camera.h"

#include <fmt/format.h>

#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "semslam/core/error.h"

namespace semslam {
namespace {

Eigen::Vector2d Distort(const Distortion& d, const Eigen::Vector2d& n) {
  const double x = n.x(), y = n.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  return {x * radial + 2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x),
          y * radial + d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y};
}

}  // namespace

void PinholeCamera::Check() const {
  Require(width > 0 && height > 0, fmt::format("camera: image size {}x{} must be positive", width, height));
  Require(std::isfinite(fx) && fx > 0, fmt::format("camera: fx = {} must be positive", fx));
  Require(std::isfinite(fy) && fy > 0, fmt::format("camera: fy = {} must be positive", fy));
  Require(std::isfinite(cx) && std::isfinite(cy), "camera: principal point must be finite");
  Require(std::isfinite(distortion.k1) && std::isfinite(distortion.k2) && std::isfinite(distortion.p1) &&
              std::isfinite(distortion.p2) && std::isfinite(distortion.k3),
          "camera: distortion coefficients must be finite");
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d k;
  k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
  return k;
}

Eigen::Vector2d PinholeCamera::Project(const Eigen::Vector3d& p) const {
  Eigen::Vector2d n(p.x() / p.z(), p.y() / p.z());
  if (!distortion.IsZero()) n = Distort(distortion, n);
  return {fx * n.x() + cx, fy * n.y() + cy};
}

std::optional<Eigen::Vector2d> PinholeCamera::ProjectIfVisible(const Eigen::Vector3d& p, double margin) const {
  if (!(p.z() > 0)) return std::nullopt;
  const Eigen::Vector2d uv = Project(p);
  if (!InImage(uv, margin)) return std::nullopt;
  return uv;
}

Eigen::Vector2d PinholeCamera::PixelToNormalized(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d distorted((pixel.x() - cx) / fx, (pixel.y() - cy) / fy);
  if (distortion.IsZero()) return distorted;
  // Fixed-point iteration; converges in a handful of steps for lenses of practical distortion.
  Eigen::Vector2d n = distorted;
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector2d error = Distort(distortion, n) - distorted;
    n -= error;
    if (error.squaredNorm() < 1e-24) break;
  }
  return n;
}

std::optional<Eigen::Vector2d> PinholeCamera::PixelNotUndistorted() const {
  if (distortion.IsZero()) return std::nullopt;
  constexpr int kSteps = 32;
  constexpr double kTolerancePx = 0.1;
  const double w = width - 1.0, h = height - 1.0;
  // The four sides, each walked in the direction its undistorted coordinate must grow.
  const std::array<std::pair<Eigen::Vector2d, Eigen::Vector2d>, 4> sides = {
      std::pair{Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0)},
      {Eigen::Vector2d(0, h), Eigen::Vector2d(w, h)},
      {Eigen::Vector2d(0, 0), Eigen::Vector2d(0, h)},
      {Eigen::Vector2d(w, 0), Eigen::Vector2d(w, h)}};
  for (size_t side = 0; side < sides.size(); ++side) {
    const int axis = side < 2 ? 0 : 1;
    double previous = -std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kSteps; ++i) {
      const Eigen::Vector2d pixel =
          sides[side].first + (sides[side].second - sides[side].first) * (static_cast<double>(i) / kSteps);
      const Eigen::Vector2d n = PixelToNormalized(pixel);
      if (!n.allFinite() || (Project(n.homogeneous()) - pixel).norm() > kTolerancePx || !(n[axis] > previous))
        return pixel;
      previous = n[axis];
    }
  }
  return std::nullopt;
}

Eigen::Vector3d PinholeCamera::Unproject(const Eigen::Vector2d& pixel) const {
  const Eigen::Vector2d n = PixelToNormalized(pixel);
  return Eigen::Vector3d(n.x(), n.y(), 1.0).normalized();
}

PinholeCamera PinholeCamera::Scaled(double factor) const {
  PinholeCamera c = *this;
  c.width = static_cast<int>(std::lround(width * factor));
  c.height = static_cast<int>(std::lround(height * factor));
  // Pixel centres: u' + 0.5 = factor * (u + 0.5).
  c.fx = fx * factor;
  c.fy = fy * factor;
  c.cx = (cx + 0.5) * factor - 0.5;
  c.cy = (cy + 0.5) * factor - 0.5;
  return c;
}

std::string PinholeCamera::ToString() const {
  return fmt::format("{}x{} fx={:.3f} fy={:.3f} cx={:.3f} cy={:.3f}", width, height, fx, fy, cx, cy);
}

void StereoRig::Check() const {
  left.Check();
  Require(std::isfinite(baseline) && baseline > 0, fmt::format("stereo: baseline = {} must be positive", baseline));
}

}  // namespace semslam
