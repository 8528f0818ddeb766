#include "semslam/geo/wgs84.h"

#include <fmt/format.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>

#include "semslam/core/error.h"

namespace semslam {

bool Wgs84::IsValid() const {
  return std::isfinite(latitude_deg) && std::isfinite(longitude_deg) && std::isfinite(altitude_m) &&
         std::abs(latitude_deg) <= 90.0 && std::abs(longitude_deg) <= 180.0;
}

std::string Wgs84::ToString() const {
  return fmt::format("({:.8f}, {:.8f}, {:.3f} m)", latitude_deg, longitude_deg, altitude_m);
}

struct EnuFrame::Impl {
  GeographicLib::LocalCartesian projection;
};

EnuFrame::EnuFrame(const Wgs84& origin) : origin_(origin) {
  Require(origin.IsValid(), "ENU origin is not a valid WGS84 position: " + origin.ToString());
  impl_ = std::make_unique<Impl>(
      Impl{GeographicLib::LocalCartesian(origin.latitude_deg, origin.longitude_deg, origin.altitude_m)});
}

EnuFrame::~EnuFrame() = default;
EnuFrame::EnuFrame(const EnuFrame& other)
    : origin_(other.origin_), impl_(std::make_unique<Impl>(*other.impl_)) {}
EnuFrame& EnuFrame::operator=(const EnuFrame& other) {
  if (this != &other) {
    origin_ = other.origin_;
    impl_ = std::make_unique<Impl>(*other.impl_);
  }
  return *this;
}

Eigen::Vector3d EnuFrame::ToEnu(const Wgs84& p) const {
  Eigen::Vector3d enu;
  impl_->projection.Forward(p.latitude_deg, p.longitude_deg, p.altitude_m, enu.x(), enu.y(), enu.z());
  return enu;
}

Wgs84 EnuFrame::ToWgs84(const Eigen::Vector3d& enu) const {
  Wgs84 p;
  impl_->projection.Reverse(enu.x(), enu.y(), enu.z(), p.latitude_deg, p.longitude_deg, p.altitude_m);
  return p;
}

}  // namespace semslam
