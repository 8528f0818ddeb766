#include "semslam/sim/gps_sim.h"

#include <cmath>

#include "semslam/sim/random.h"

namespace semslam::sim {
namespace {
// Rounds away the numerical dust of the path smoothing (1e-12 m/s is no measurement).
double Clean(double v, double scale = 1e6) {
  const double r = std::round(v * scale) / scale;
  return r == 0.0 ? 0.0 : r;
}
}  // namespace

std::vector<StampedOxts> SimulateOxts(const SyntheticCity& sim) {
  const GpsOptions& gps = sim.options().gps;
  const Route& route = sim.route();
  // A fleet drive (route_seed) has its own GPS noise, as drives on other days do.
  const std::uint64_t route_seed = sim.options().route.route_seed;
  const std::uint64_t town_seed = HashCombine(sim.options().city.seed, 0x6b5);
  const std::uint64_t seed = gps.seed != 0     ? gps.seed
                             : route_seed == 0 ? town_seed
                                               : HashCombine(town_seed, Hash3(13, route_seed, 3));
  std::vector<StampedOxts> readings;
  for (size_t f = 0; f < sim.num_frames(); f += static_cast<size_t>(gps.every)) {
    Rng rng = Rng::Stream(seed, f);
    const bool dropped = rng.Bernoulli(gps.dropout);
    const bool outlier = rng.Bernoulli(gps.outliers);
    const double outlier_angle = rng.Uniform(0.0, 2.0 * M_PI);
    // One draw per statement (random.h), the last axis first as GCC's builds drew them.
    const double noise_up = rng.Gaussian();
    const double noise_north = rng.Gaussian();
    const double noise_east = rng.Gaussian();
    const Eigen::Vector3d noise(noise_east, noise_north, noise_up);
    if (dropped && f != 0) continue;
    const Rigid3d& town_from_camera = route.town_from_camera[f];
    Eigen::Vector3d enu = town_from_camera.translation + gps.noise * noise;
    if (outlier)
      enu += gps.outlier_distance * Eigen::Vector3d(std::cos(outlier_angle), std::sin(outlier_angle), 0.0);
    const Wgs84 position = sim.enu().ToWgs84(enu);
    OxtsRecord r;
    r.lat = position.latitude_deg;
    r.lon = position.longitude_deg;
    r.alt = position.altitude_m;
    r.roll = 0.0;
    r.pitch = 0.0;
    r.yaw = Clean(route.yaw[f], 1e12);  // 0 = east, counter-clockwise positive
    const double v = route.speed[f];
    r.ve = Clean(v * std::cos(route.yaw[f]));
    r.vn = Clean(v * std::sin(route.yaw[f]));
    r.vf = Clean(v);
    r.vl = 0.0;
    r.vu = 0.0;
    constexpr double kGravity = 9.81;
    const double lateral = Clean(v * route.yaw_rate[f]);  // centripetal, towards the left in a left turn
    r.ax = r.af = Clean(route.acceleration[f]);
    r.ay = r.al = lateral;
    r.az = r.au = kGravity;
    r.wx = r.wf = 0.0;
    r.wy = r.wl = 0.0;
    r.wz = r.wu = Clean(route.yaw_rate[f], 1e8);
    r.pos_accuracy = gps.noise;
    r.vel_accuracy = 0.05;
    r.navstat = 4;
    r.numsats = 9;
    r.posmode = 5;
    r.velmode = 5;
    r.orimode = 6;
    readings.push_back({gps.start_epoch + sim.Timestamp(f), r});
  }
  return readings;
}

int OxtsFrame(const SyntheticCity& sim, const StampedOxts& reading) {
  return static_cast<int>(
      std::lround((reading.timestamp - sim.options().gps.start_epoch) * sim.options().route.rate_hz));
}

}  // namespace semslam::sim
