// Poses of a KITTI raw drive from its OXTS readings, in the raw devkit's convention.

#include <cmath>

#include "semslam/io/kitti_raw.h"

namespace semslam {

namespace {
constexpr double kEarthRadius = 6378137.0;  // metres, the devkit's (WGS84 equatorial radius)
constexpr double kDegree = M_PI / 180.0;
}  // namespace

double OxtsMercatorScale(double first_latitude_deg) { return std::cos(first_latitude_deg * kDegree); }

Rigid3d OxtsWorldFromImu(const OxtsRecord& record, double mercator_scale) {
  const Eigen::Vector3d position(
      mercator_scale * kEarthRadius * record.lon * kDegree,
      mercator_scale * kEarthRadius * std::log(std::tan((90.0 + record.lat) * kDegree / 2.0)), record.alt);
  const Eigen::Matrix3d rotation = (Eigen::AngleAxisd(record.yaw, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(record.pitch, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(record.roll, Eigen::Vector3d::UnitX()))
                                       .toRotationMatrix();
  return Rigid3d(rotation, position);
}

std::vector<Rigid3d> OxtsCameraPoses(const std::vector<OxtsRecord>& records, const Rigid3d& camera_from_imu) {
  std::vector<Rigid3d> poses;
  if (records.empty()) return poses;
  const double scale = OxtsMercatorScale(records.front().lat);
  const Rigid3d imu_from_camera = camera_from_imu.Inverse();
  // Everything relative to the first reading's IMU pose first: the Mercator coordinates are millions of
  // metres, and composing them with centimetre offsets directly would lose digits.
  const Rigid3d first_from_world = OxtsWorldFromImu(records.front(), scale).Inverse();
  poses.reserve(records.size());
  for (const OxtsRecord& record : records) {
    const Rigid3d imu0_from_imu = first_from_world * OxtsWorldFromImu(record, scale);
    poses.push_back(camera_from_imu * imu0_from_imu * imu_from_camera);
  }
  return poses;
}

}  // namespace semslam
