#pragma once
// WGS84 geodetic coordinates and the local East-North-Up frame around an origin (GeographicLib).

#include <memory>
#include <string>

#include "semslam/geometry/eigen_types.h"

namespace semslam {

struct Wgs84 {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double altitude_m = 0.0;

  // Finite, latitude within [-90, 90], longitude within [-180, 180].
  bool IsValid() const;
  std::string ToString() const;
};

// ENU: x east, y north, z up, metres, tangent to the WGS84 ellipsoid at the origin.
class EnuFrame {
 public:
  // Throws InvalidArgument if the origin is not a valid position.
  explicit EnuFrame(const Wgs84& origin);
  ~EnuFrame();
  EnuFrame(const EnuFrame& other);
  EnuFrame& operator=(const EnuFrame& other);

  Eigen::Vector3d ToEnu(const Wgs84& position) const;
  Wgs84 ToWgs84(const Eigen::Vector3d& enu) const;
  const Wgs84& origin() const { return origin_; }

 private:
  struct Impl;
  Wgs84 origin_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace semslam
