#pragma once
// A driven route in ENU for GPS tests: a block loop with turns and a gentle grade, one position per frame.

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "semslam/geo/frame_position.h"
#include "semslam/geo/gps.h"
#include "semslam/geometry/eigen_types.h"

namespace semslam::testing {

// Corners of the route (ENU metres), driven in order at `step_m` per frame; altitude varies by a few metres.
inline Points3d DriveThrough(const std::vector<Eigen::Vector2d>& corners, double step_m) {
  Points3d points;
  double s = 0.0;
  for (size_t i = 0; i + 1 < corners.size(); ++i) {
    const Eigen::Vector2d a = corners[i], b = corners[i + 1];
    const double length = (b - a).norm();
    for (double t = points.empty() ? 0.0 : step_m - std::fmod(s, step_m); t < length; t += step_m) {
      const Eigen::Vector2d p = a + (b - a) * (t / length);
      const double total = s + t;
      points.emplace_back(p.x(), p.y(), 3.0 * std::sin(total / 150.0));
    }
    s += length;
  }
  return points;
}

inline Points3d BlockLoop() {
  return DriveThrough({{0, 0}, {400, 0}, {400, 300}, {0, 300}, {0, 0}, {200, 0}, {200, 150}}, 1.0);
}

inline Eigen::Vector3d Noise3(std::mt19937& rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(rng), n(rng), n(rng)};
}

// 400 m straight north-east up a 2 % grade: every position on one line.
inline Points3d StraightRoad() {
  Points3d points;
  for (int i = 0; i < 400; ++i) {
    const double s = static_cast<double>(i);
    points.emplace_back(s * std::cos(0.6), s * std::sin(0.6), 0.02 * s);
  }
  return points;
}

// A monocular drive: the true ENU trajectory of `route` (BlockLoop: 1750 m, a frame per metre at 10 Hz), and
// the SLAM map of it, which starts at the first camera (KITTI's world) at `map_scale` units per metre and
// drifts: its scale grows by `scale_drift` per 100 m and its heading turns by `yaw_drift_deg` per 100 m.
struct Drive {
  Points3d truth_enu;             // camera centres, per frame
  std::vector<Rigid3d> truth;     // enu_from_camera, per frame
  std::vector<double> map_scale;  // map units per metre at each frame
  std::vector<FramePose> frames;  // the SLAM map's poses, per frame
  std::vector<GpsFix> fixes;
  std::vector<bool> outlier;
  EnuFrame enu{Wgs84{49.0, 8.4, 115.0}};
};

inline Rigid3d EnuFromCamera(const Eigen::Vector3d& position, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d forward = Eigen::Vector3d(direction.x(), direction.y(), 0).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ());
  Eigen::Matrix3d r;
  r.col(0) = right;
  r.col(1) = -Eigen::Vector3d::UnitZ();
  r.col(2) = forward;
  return Rigid3d(r, position);
}

inline Drive MakeDrive(double scale_drift, double yaw_drift_deg, double map_scale, double gps_sigma,
                       int gps_every, double outlier_fraction, unsigned seed,
                       const Points3d& route = BlockLoop()) {
  Drive d;
  d.truth_enu = route;
  const size_t n = d.truth_enu.size();
  std::vector<Rigid3d>& truth = d.truth;
  truth.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d dir =
        i + 1 < n ? d.truth_enu[i + 1] - d.truth_enu[i] : d.truth_enu[i] - d.truth_enu[i - 1];
    truth[i] = EnuFromCamera(d.truth_enu[i], dir);
  }
  Rigid3d map_from_camera;  // identity: the map is the first camera's frame
  double travelled = 0.0;
  for (size_t i = 0; i < n; ++i) {
    if (i > 0) {
      Rigid3d step = truth[i - 1].Inverse() * truth[i];  // metres, camera i-1 frame
      travelled += step.translation.norm();
      const double scale = map_scale * std::pow(1.0 + scale_drift, travelled / 100.0);
      step.translation *= scale;
      // Heading drift: a turn about the camera's vertical (y) axis.
      const double yaw = yaw_drift_deg * std::numbers::pi / 180.0 * step.translation.norm() / scale / 100.0;
      step.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY())) * step.rotation;
      map_from_camera = map_from_camera * step;
    }
    d.map_scale.push_back(map_scale * std::pow(1.0 + scale_drift, travelled / 100.0));
    d.frames.push_back(FramePose{i, -1, 0.1 * static_cast<double>(i), map_from_camera});
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < n; i += static_cast<size_t>(gps_every)) {
    Eigen::Vector3d enu = d.truth_enu[i] + Noise3(rng, gps_sigma);
    const bool bad = u(rng) < outlier_fraction;
    if (bad) {
      const double angle = 2 * std::numbers::pi * u(rng);
      enu = d.truth_enu[i] + Eigen::Vector3d(50 * std::cos(angle), 50 * std::sin(angle), 0.0);
    }
    d.outlier.push_back(bad);
    d.fixes.push_back(GpsFix{0.1 * static_cast<double>(i), d.enu.ToWgs84(enu), gps_sigma, {}});
  }
  return d;
}

}  // namespace semslam::testing
