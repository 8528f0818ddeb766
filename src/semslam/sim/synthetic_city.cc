#include "semslam/sim/synthetic_city.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "semslam/core/error.h"
#include "semslam/sim/random.h"

namespace semslam::sim {

void CameraOptions::Check() const {
  Require(width >= 16 && width <= 8192 && height >= 16 && height <= 8192,
          "CameraOptions: width and height must be in [16, 8192]");
  Require(std::isfinite(focal) && focal > 1, "CameraOptions.focal must be > 1 pixel");
  Require(std::isfinite(baseline) && baseline > 0 && baseline < 10,
          "CameraOptions.baseline must be in (0, 10) m");
}

void GpsOptions::Check() const {
  Require(origin.IsValid(), "GpsOptions.origin must be a valid WGS84 position");
  Require(std::isfinite(noise) && noise >= 0 && noise <= 1000, "GpsOptions.noise must be in [0, 1000] m");
  Require(every >= 1, "GpsOptions.every must be >= 1");
  Require(std::isfinite(dropout) && dropout >= 0 && dropout < 1, "GpsOptions.dropout must be in [0, 1)");
  Require(std::isfinite(outliers) && outliers >= 0 && outliers <= 1, "GpsOptions.outliers must be in [0, 1]");
  Require(std::isfinite(outlier_distance) && outlier_distance >= 0,
          "GpsOptions.outlier_distance must be >= 0");
  Require(std::isfinite(start_epoch) && start_epoch >= 0 && start_epoch < 4e9,
          "GpsOptions.start_epoch must be Unix seconds in [0, 4e9)");
}

void SynthOptions::Check() const {
  city.Check();
  route.Check();
  camera.Check();
  render.Check();
  gps.Check();
}

std::vector<std::string> PresetNames() { return {"default", "small", "dense", "static"}; }

SynthOptions PresetOptions(std::string_view name) {
  SynthOptions o;
  o.preset = std::string(name);
  if (name == "default") return o;
  if (name == "small") {
    o.city.blocks_x = 5;
    o.city.blocks_y = 5;
    o.city.park_blocks = 1;
    return o;
  }
  if (name == "dense") {
    o.city.parked_car_density = 0.85;
    o.city.person_density = 0.03;
    o.city.bicycle_density = 0.015;
    o.city.tree_density = 0.85;
    return o;
  }
  if (name == "static") {
    o.city.parked_car_density = 0.0;
    o.city.person_density = 0.0;
    o.city.bicycle_density = 0.0;
    return o;
  }
  std::string names;
  for (const std::string& n : PresetNames()) names += (names.empty() ? "" : ", ") + n;
  throw InvalidArgument("unknown synthetic city preset '" + std::string(name) + "' (known: " + names + ")");
}

SyntheticCity::SyntheticCity(const SynthOptions& options) : options_(options) {
  options.Check();
  city_ = GenerateCity(options.city);
  route_ = PlanRoute(city_, options.route);
  rig_.left.width = options.camera.width;
  rig_.left.height = options.camera.height;
  rig_.left.fx = rig_.left.fy = options.camera.focal;
  rig_.left.cx = 0.5 * (options.camera.width - 1);
  rig_.left.cy = 0.5 * (options.camera.height - 1);
  rig_.baseline = options.camera.baseline;
  rig_.Check();
  enu_from_world_ = route_.town_from_camera.front();
  enu_ = std::make_unique<EnuFrame>(options.gps.origin);
  index_ = std::make_unique<SceneIndex>(city_);
  renderer_ = std::make_unique<Renderer>(city_, *index_, rig_.left, options.render);
}

SyntheticCity::~SyntheticCity() = default;

Rigid3d SyntheticCity::WorldFromCamera(size_t frame) const {
  Require(frame < num_frames(), "SyntheticCity::WorldFromCamera: frame out of range");
  return enu_from_world_.Inverse() * route_.town_from_camera[frame];
}

std::vector<Rigid3d> SyntheticCity::WorldFromCameraAll() const {
  std::vector<Rigid3d> poses;
  poses.reserve(num_frames());
  for (size_t f = 0; f < num_frames(); ++f) poses.push_back(WorldFromCamera(f));
  return poses;
}

Wgs84 SyntheticCity::ToWgs84(const Eigen::Vector3d& world_point) const {
  return enu_->ToWgs84(enu_from_world_ * world_point);
}

RenderedFrame SyntheticCity::Render(size_t frame, unsigned parts) const {
  Require(frame < num_frames(), "SyntheticCity::Render: frame out of range");
  RenderedFrame out;
  const Rigid3d& town_from_left = route_.town_from_camera[frame];
  // A fleet drive has its own sensor noise; today's drive keeps the noise it has always had.
  const std::uint64_t noise_seed =
      options_.route.route_seed == 0
          ? options_.city.seed
          : HashCombine(options_.city.seed, Hash3(13, options_.route.route_seed, 2));
  const auto seed32 = static_cast<std::uint32_t>(Mix64(noise_seed));
  const auto key = [&](std::uint32_t camera) {
    return Hash32(seed32, static_cast<std::uint32_t>(frame), camera);
  };
  const bool want_left = (parts & (kRenderLeft | kRenderLabels | kRenderDepth)) != 0;
  if (want_left) {
    cv::Mat grey;
    renderer_->Render(town_from_left, key(0), &grey, (parts & kRenderLabels) ? &out.labels : nullptr,
                      (parts & kRenderDepth) ? &out.depth : nullptr);
    if (parts & kRenderLeft) out.left = grey;
  }
  if (parts & kRenderRight) {
    const Rigid3d left_from_right(Eigen::Quaterniond::Identity(), Eigen::Vector3d(rig_.baseline, 0, 0));
    renderer_->Render(town_from_left * left_from_right, key(1), &out.right);
  }
  return out;
}

SurfaceClass SyntheticCity::ClassAt(const Eigen::Vector3d& world_point) const {
  const Eigen::Vector3d town = enu_from_world_ * world_point;
  const NearestSurface n = index_->Nearest(town.cast<float>());
  SurfaceClass c;
  c.label = n.label;
  c.distance = n.distance;
  c.object =
      n.primitive < 0 ? -1 : static_cast<int>(city_.primitives[static_cast<size_t>(n.primitive)].object);
  return c;
}

std::vector<RouteLandmark> SyntheticCity::Landmarks() const {
  constexpr double kAlongRoute = 60.0;  // metres from the driven path
  constexpr size_t kMin = 8, kMax = 20;
  std::vector<RouteLandmark> all;
  const Rigid3d world_from_town = WorldFromTown();
  for (const Place& place : city_.places) {
    RouteLandmark l;
    l.place = &place;
    l.distance = std::numeric_limits<double>::max();
    for (size_t f = 0; f < num_frames(); ++f) {
      const double d = (route_.town_from_camera[f].translation.head<2>() - place.position.head<2>()).norm();
      if (d < l.distance) {
        l.distance = d;
        l.nearest_frame = static_cast<int>(f);
      }
    }
    l.world = world_from_town * place.position;
    l.wgs84 = enu_->ToWgs84(place.position);
    all.push_back(l);
  }
  // The nearest ones: all within reach of the route, at least kMin, at most kMax.
  std::stable_sort(all.begin(), all.end(),
                   [](const RouteLandmark& a, const RouteLandmark& b) { return a.distance < b.distance; });
  size_t keep = 0;
  while (keep < all.size() && all[keep].distance <= kAlongRoute) ++keep;
  keep = std::min(std::max(keep, std::min(kMin, all.size())), kMax);
  all.resize(keep);
  std::stable_sort(all.begin(), all.end(), [](const RouteLandmark& a, const RouteLandmark& b) {
    return a.nearest_frame != b.nearest_frame ? a.nearest_frame < b.nearest_frame
                                              : a.place->name < b.place->name;
  });
  return all;
}

std::vector<Revisit> SyntheticCity::Revisits(double max_distance, double max_angle_deg, int min_gap) const {
  Require(max_distance > 0 && max_angle_deg > 0 && min_gap >= 1, "SyntheticCity::Revisits: bad thresholds");
  const double cos_max = std::cos(max_angle_deg * M_PI / 180.0);
  std::vector<Revisit> out;
  bool in_run = false;
  const int n = static_cast<int>(num_frames());
  for (int f = 0; f < n; ++f) {
    const Rigid3d& a = route_.town_from_camera[static_cast<size_t>(f)];
    const Eigen::Vector3d za = a.rotation * Eigen::Vector3d::UnitZ();
    Revisit best;
    best.frame = -1;
    double best_d = max_distance;
    for (int g = 0; g + min_gap <= f; ++g) {
      const Rigid3d& b = route_.town_from_camera[static_cast<size_t>(g)];
      const double d = (a.translation - b.translation).norm();
      if (d > best_d) continue;
      const double c = za.dot(b.rotation * Eigen::Vector3d::UnitZ());
      if (c < cos_max) continue;
      best_d = d;
      best = {f, g, d, std::acos(std::min(1.0, c)) * 180.0 / M_PI};
    }
    if (best.frame >= 0 && !in_run) out.push_back(best);
    in_run = best.frame >= 0;
  }
  return out;
}

}  // namespace semslam::sim
