#include "semslam/landmarks/landmark_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "semslam/core/error.h"

namespace semslam {

void LandmarkOptions::Check() const {
  Require(std::isfinite(sigma_m) && sigma_m > 0, "landmark sigma_m must be positive");
  Require(max_association_distance_m > 0, "landmark max_association_distance_m must be positive");
}

Membership GaussianMembership(double distance_m, double sigma_m) {
  const double q = distance_m * distance_m / (2.0 * sigma_m * sigma_m);
  const double value = std::exp(-q);
  return Membership{value, value / (2.0 * std::numbers::pi * sigma_m * sigma_m)};
}

Membership GaussianMembership(const Eigen::Vector2d& position, const Eigen::Vector2d& landmark,
                              double sigma_m) {
  return GaussianMembership((position - landmark).norm(), sigma_m);
}

std::vector<PlacedLandmark> PlaceLandmarks(const std::vector<Landmark>& catalogue,
                                           const Georeference& georeference, const FramePositions& keyframes,
                                           const LandmarkOptions& options) {
  options.Check();
  Points3d keyframe_enu;
  keyframe_enu.reserve(keyframes.size());
  for (const FramePosition& k : keyframes) keyframe_enu.push_back(georeference.MapToEnu(k.map_position));

  std::vector<PlacedLandmark> placed;
  placed.reserve(catalogue.size());
  for (const Landmark& landmark : catalogue) {
    PlacedLandmark p;
    p.landmark = landmark;
    // Without an altitude, the horizontal position is taken at the origin's height first (the ellipsoid's
    // height 0 could be hundreds of metres below the area and bend east/north by centimetres per km).
    Wgs84 position = landmark.position;
    if (!landmark.has_altitude) position.altitude_m = georeference.enu_frame.origin().altitude_m;
    p.enu = georeference.enu_frame.ToEnu(position);
    int nearest = -1;
    double nearest_distance = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < keyframe_enu.size(); ++k) {
      const double d = (keyframe_enu[k].head<2>() - p.enu.head<2>()).norm();
      if (d < nearest_distance) {
        nearest_distance = d;
        nearest = static_cast<int>(k);
      }
    }
    if (!landmark.has_altitude && nearest >= 0) {
      // At the nearest keyframe's height (the camera's: the landmark is placed on the driven level).
      const Eigen::Vector3d& k = keyframe_enu[static_cast<size_t>(nearest)];
      position.altitude_m = georeference.enu_frame.ToWgs84(k).altitude_m;
      p.enu = georeference.enu_frame.ToEnu(position);
      p.enu.z() = k.z();
      nearest_distance = (k.head<2>() - p.enu.head<2>()).norm();
    }
    if (!landmark.has_altitude && nearest < 0) p.enu.z() = 0.0;
    if (nearest >= 0 && nearest_distance <= options.max_association_distance_m) {
      p.nearest_keyframe = nearest;
      p.keyframe_distance_m = nearest_distance;
      p.keyframe_membership = GaussianMembership(nearest_distance, options.sigma_m);
    } else if (nearest >= 0) {
      p.keyframe_distance_m = nearest_distance;
    }
    // Into the map near the associated keyframe (the same place may be in a drifting map twice).
    p.map_position =
        nearest >= 0 ? georeference.EnuToMapAt(p.enu, keyframes[static_cast<size_t>(nearest)].map_position)
                     : georeference.EnuToMap(p.enu);
    placed.push_back(std::move(p));
  }
  return placed;
}

std::vector<std::vector<Membership>> KeyframeMemberships(const FramePositions& keyframes,
                                                         const std::vector<PlacedLandmark>& landmarks,
                                                         const Georeference& georeference, double sigma_m) {
  Require(std::isfinite(sigma_m) && sigma_m > 0, "membership sigma_m must be positive");
  std::vector<std::vector<Membership>> table(keyframes.size(), std::vector<Membership>(landmarks.size()));
  for (size_t k = 0; k < keyframes.size(); ++k) {
    const Eigen::Vector2d p = georeference.MapToEnu(keyframes[k].map_position).head<2>();
    for (size_t l = 0; l < landmarks.size(); ++l) {
      table[k][l] = GaussianMembership(p, landmarks[l].enu.head<2>(), sigma_m);
    }
  }
  return table;
}

std::vector<NearLandmark> NearestLandmarks(const Eigen::Vector3d& map_position,
                                           const std::vector<PlacedLandmark>& landmarks,
                                           const Georeference& georeference, double sigma_m,
                                           size_t max_count) {
  Require(std::isfinite(sigma_m) && sigma_m > 0, "membership sigma_m must be positive");
  const Eigen::Vector2d p = georeference.MapToEnu(map_position).head<2>();
  std::vector<NearLandmark> near;
  near.reserve(landmarks.size());
  for (size_t l = 0; l < landmarks.size(); ++l) {
    const double d = (landmarks[l].enu.head<2>() - p).norm();
    near.push_back(NearLandmark{static_cast<int>(l), d, GaussianMembership(d, sigma_m)});
  }
  const size_t count = std::min(max_count, near.size());
  std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(count), near.end(),
                    [](const NearLandmark& a, const NearLandmark& b) { return a.distance_m < b.distance_m; });
  near.resize(count);
  return near;
}

MembershipRaster RasterizeMembership(const std::vector<PlacedLandmark>& landmarks,
                                     const Eigen::Vector2d& enu_min, const Eigen::Vector2d& enu_max,
                                     double cell_m, double sigma_m, size_t max_cells) {
  Require(std::isfinite(sigma_m) && sigma_m > 0, "membership sigma_m must be positive");
  Require(std::isfinite(cell_m) && cell_m > 0, "raster cell size must be positive");
  Require(enu_min.allFinite() && enu_max.allFinite() && (enu_max.array() >= enu_min.array()).all(),
          "raster bounds must be finite with max >= min");
  Require(max_cells >= 1, "raster max_cells must be at least 1");
  const Eigen::Vector2d size = enu_max - enu_min;
  const auto cells_for = [&](double c) {
    return std::max(1.0, std::ceil(size.x() / c)) * std::max(1.0, std::ceil(size.y() / c));
  };
  while (cells_for(cell_m) > static_cast<double>(max_cells)) cell_m *= 1.25;

  MembershipRaster raster;
  raster.origin = enu_min;
  raster.cell_m = cell_m;
  raster.cols = static_cast<int>(std::max(1.0, std::ceil(size.x() / cell_m)));
  raster.rows = static_cast<int>(std::max(1.0, std::ceil(size.y() / cell_m)));
  const size_t n = static_cast<size_t>(raster.cols) * static_cast<size_t>(raster.rows);
  raster.max_membership.assign(n, 0.0f);
  raster.best_landmark.assign(n, -1);
  raster.sum_pdf.assign(n, 0.0f);
  for (int row = 0; row < raster.rows; ++row) {
    for (int col = 0; col < raster.cols; ++col) {
      const size_t i = static_cast<size_t>(row) * static_cast<size_t>(raster.cols) + static_cast<size_t>(col);
      const Eigen::Vector2d c = raster.CellCentre(col, row);
      double best = 0.0, pdf = 0.0;
      for (size_t l = 0; l < landmarks.size(); ++l) {
        const Membership m = GaussianMembership(c, landmarks[l].enu.head<2>(), sigma_m);
        pdf += m.pdf;
        if (m.value > best) {
          best = m.value;
          if (m.value >= 1e-6) raster.best_landmark[i] = static_cast<int>(l);
        }
      }
      raster.max_membership[i] = static_cast<float>(best);
      raster.sum_pdf[i] = static_cast<float>(pdf);
    }
  }
  return raster;
}

}  // namespace semslam
