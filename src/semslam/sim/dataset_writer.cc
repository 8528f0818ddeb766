#include "semslam/sim/dataset_writer.h"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <nlohmann/json.hpp>
#include <system_error>

#include "semslam/core/atomic_file.h"
#include "semslam/core/error.h"
#include "semslam/core/interrupt.h"
#include "semslam/core/progress.h"
#include "semslam/io/kitti_odometry.h"
#include "semslam/io/kitti_raw.h"
#include "semslam/io/sequence.h"
#include "semslam/io/trajectory_io.h"
#include "semslam/semantics/class_table.h"
#include "semslam/sim/gps_sim.h"

namespace semslam::sim {
namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

namespace {

double Round(double v, double decimals_scale = 1000.0) {
  const double r = std::round(v * decimals_scale) / decimals_scale;
  return r == 0.0 ? 0.0 : r;  // no "-0"
}
Json Vec(const Eigen::Vector3d& v, double scale = 1000.0) {
  return Json::array({Round(v.x(), scale), Round(v.y(), scale), Round(v.z(), scale)});
}

const char* ShapeName(Shape s) {
  switch (s) {
    case Shape::kBox:
      return "box";
    case Shape::kCylinder:
      return "cylinder";
    case Shape::kEllipsoid:
      return "ellipsoid";
  }
  return "box";
}

std::string FrameName(size_t frame) { return fmt::format("{:06d}.png", frame); }

// Removes numbered files from an earlier, longer run so that the folder matches this one.
void RemoveStale(const fs::path& dir, size_t first) {
  std::error_code ec;
  for (size_t f = first; fs::exists(dir / FrameName(f), ec); ++f) fs::remove(dir / FrameName(f), ec);
}

Json OptionsJson(const SynthOptions& o) {
  Json j;
  j["preset"] = o.preset;
  j["city"] = {{"seed", o.city.seed},
               {"traffic_seed", o.city.traffic_seed != 0 ? o.city.traffic_seed : o.city.seed},
               {"blocks_x", o.city.blocks_x},
               {"blocks_y", o.city.blocks_y},
               {"min_block", o.city.min_block},
               {"max_block", o.city.max_block},
               {"parked_car_density", o.city.parked_car_density},
               {"person_density", o.city.person_density},
               {"bicycle_density", o.city.bicycle_density},
               {"tree_density", o.city.tree_density},
               {"park_blocks", o.city.park_blocks}};
  j["route"] = {{"frames", o.route.frames},
                {"rate_hz", o.route.rate_hz},
                {"min_speed", o.route.min_speed},
                {"max_speed", o.route.max_speed},
                {"camera_height", o.route.camera_height},
                {"reverse", o.route.reverse},
                {"seed", o.route.seed != 0 ? o.route.seed : o.city.seed}};
  // Only for a fleet drive: today's scene.json stays as it was.
  if (o.route.route_seed != 0) j["route"]["route_seed"] = o.route.route_seed;
  j["camera"] = {{"width", o.camera.width},
                 {"height", o.camera.height},
                 {"focal", o.camera.focal},
                 {"baseline", o.camera.baseline}};
  j["render"] = {
      {"sensor_noise", o.render.sensor_noise},          {"max_distance", o.render.max_distance},
      {"haze_distance", o.render.haze_distance},        {"ambient", o.render.ambient},
      {"sun_strength", o.render.sun_strength},          {"sun_azimuth_deg", o.render.sun_azimuth_deg},
      {"sun_elevation_deg", o.render.sun_elevation_deg}};
  j["gps"] = {{"noise", o.gps.noise},
              {"every", o.gps.every},
              {"dropout", o.gps.dropout},
              {"outliers", o.gps.outliers},
              {"outlier_distance", o.gps.outlier_distance},
              {"seed", o.gps.seed}};
  return j;
}

}  // namespace

void DatasetOptions::Check() const {
  Require(!sequence.empty() && sequence.find('/') == std::string::npos,
          "DatasetOptions.sequence must be a plain name");
  Require(png_compression >= 0 && png_compression <= 9, "DatasetOptions.png_compression must be in 0..9");
}

std::string SceneJson(const SyntheticCity& sim) {
  const City& city = sim.city();
  const Route& route = sim.route();
  const StreetGrid& grid = city.grid;
  const Rigid3d world_from_town = sim.WorldFromTown();
  const Rigid3d& enu_from_world = sim.EnuFromWorld();
  const SynthOptions& o = sim.options();
  Json j;
  j["format"] = "semslam synthetic city";
  j["version"] = 1;
  j["seed"] = o.city.seed;
  j["options"] = OptionsJson(o);
  j["origin"] = {{"latitude", o.gps.origin.latitude_deg},
                 {"longitude", o.gps.origin.longitude_deg},
                 {"altitude", o.gps.origin.altitude_m}};
  j["start_epoch"] = o.gps.start_epoch;
  j["frames"] = sim.num_frames();
  j["rate_hz"] = o.route.rate_hz;
  const PinholeCamera& cam = sim.rig().left;
  j["camera"] = {
      {"width", cam.width}, {"height", cam.height},          {"fx", cam.fx}, {"fy", cam.fy}, {"cx", cam.cx},
      {"cy", cam.cy},       {"baseline", sim.rig().baseline}};
  {
    const Eigen::Matrix3d r = enu_from_world.rotation.toRotationMatrix();
    Json rows = Json::array();
    for (int i = 0; i < 3; ++i)
      rows.push_back(Json::array({Round(r(i, 0), 1e12), Round(r(i, 1), 1e12), Round(r(i, 2), 1e12)}));
    const Eigen::Quaterniond& q = enu_from_world.rotation;
    j["enu_from_world"] = {{"rotation", rows},
                           {"translation", Vec(enu_from_world.translation, 1e9)},
                           {"quaternion_xyzw", Json::array({q.x(), q.y(), q.z(), q.w()})}};
    j["world_up"] = Vec(world_from_town.rotation * Eigen::Vector3d::UnitZ(), 1e12);
    j["ground_plane"] = {
        {"note", "the road surface: points p with dot(world_up, p) = offset"},
        {"offset",
         Round((world_from_town.rotation * Eigen::Vector3d::UnitZ()).dot(world_from_town.translation), 1e9)}};
  }
  // Route.
  {
    Json r;
    r["length"] = Round(route.length);
    Json positions = Json::array();
    for (size_t f = 0; f < sim.num_frames(); ++f)
      positions.push_back(Vec(sim.WorldFromCamera(f).translation));
    r["positions"] = std::move(positions);
    Json speeds = Json::array();
    for (const double v : route.speed) speeds.push_back(Round(v));
    r["speed"] = std::move(speeds);
    // The planned intersections (the frames may end before the last), and the street segments driven within
    // the frames, in order.
    Json passed = Json::array();
    for (const int id : route.intersections) passed.push_back(id);
    Json segments = Json::array();
    int last = -1;
    for (const int seg : route.frame_segment) {
      if (seg >= 0 && seg != last) segments.push_back(seg);
      last = seg;
    }
    r["driven_segments"] = std::move(segments);
    r["planned_intersections"] = std::move(passed);
    Json turns = Json::array();
    for (const RouteTurn& t : route.turns) {
      turns.push_back({{"frame", t.frame},
                       {"position", Vec(sim.WorldFromCamera(static_cast<size_t>(t.frame)).translation)},
                       {"direction", t.left ? "left" : "right"},
                       {"intersection", t.intersection}});
    }
    r["turns"] = std::move(turns);
    Json revisits = Json::array();
    for (const Revisit& v : sim.Revisits()) {
      revisits.push_back({{"frame", v.frame},
                          {"earlier_frame", v.earlier_frame},
                          {"distance", Round(v.distance)},
                          {"angle_deg", Round(v.angle_deg)}});
    }
    r["revisits"] = std::move(revisits);
    j["route"] = std::move(r);
  }
  // Street graph.
  {
    std::vector<int> driven(grid.segments.size(), 0);
    int previous = -1;
    for (const int seg : route.frame_segment) {
      if (seg >= 0 && seg != previous) ++driven[static_cast<size_t>(seg)];
      previous = seg;
    }
    Json nodes = Json::array();
    for (int jj = 0; jj < grid.nj(); ++jj) {
      for (int ii = 0; ii < grid.ni(); ++ii) {
        const int id = grid.IntersectionId(ii, jj);
        const Eigen::Vector2d p = grid.Position(id);
        const Eigen::Vector3d town(p.x(), p.y(), 0.0);
        nodes.push_back({{"id", id},
                         {"i", ii},
                         {"j", jj},
                         {"position", Vec(world_from_town * town)},
                         {"enu", Vec(town)},
                         {"drivable", grid.Drivable(ii, jj)}});
      }
    }
    Json edges = Json::array();
    for (const StreetGrid::Segment& s : grid.segments) {
      edges.push_back({{"id", s.id},
                       {"from", s.a},
                       {"to", s.b},
                       {"length", Round(s.length)},
                       {"driven", driven[static_cast<size_t>(s.id)]}});
    }
    j["street_graph"] = {{"road_half_width", grid.road_half_width},
                         {"sidewalk_width", grid.sidewalk_width},
                         {"lane_offset", grid.lane_offset},
                         {"intersections", std::move(nodes)},
                         {"segments", std::move(edges)}};
  }
  // Landmarks.
  {
    Json list = Json::array();
    for (const RouteLandmark& l : sim.Landmarks()) {
      list.push_back({{"name", l.place->name},
                      {"category", l.place->category},
                      {"position", Vec(l.world)},
                      {"enu", Vec(l.place->position)},
                      {"latitude", l.wgs84.latitude_deg},
                      {"longitude", l.wgs84.longitude_deg},
                      {"altitude", Round(l.wgs84.altitude_m)},
                      {"nearest_frame", l.nearest_frame},
                      {"distance", Round(l.distance)},
                      {"object", l.place->object}});
    }
    j["landmarks"] = std::move(list);
    Json places = Json::array();
    for (const Place& p : city.places) {
      places.push_back({{"name", p.name},
                        {"category", p.category},
                        {"position", Vec(world_from_town * p.position)},
                        {"object", p.object}});
    }
    j["places"] = std::move(places);
  }
  // Classes, objects and surfaces.
  {
    Json classes = Json::array();
    for (int c = 0; c < kNumClasses; ++c) classes.push_back({{"id", c}, {"name", std::string(ClassName(c))}});
    j["classes"] = std::move(classes);
    j["ground_class"] = TrainId(SemanticClass::kRoad);
    j["sky_class"] = TrainId(SemanticClass::kSky);
    Json objects = Json::array();
    for (size_t k = 0; k < city.objects.size(); ++k) {
      const CityObject& obj = city.objects[k];
      Json e = {{"id", k}, {"kind", obj.kind}, {"class", obj.label}};
      if (!obj.name.empty()) e["name"] = obj.name;
      objects.push_back(std::move(e));
    }
    j["objects"] = std::move(objects);
    Json surfaces = Json::array();
    for (const Primitive& p : city.primitives) {
      const Eigen::Vector3d a = world_from_town * p.lo.cast<double>();
      const Eigen::Vector3d b = world_from_town * p.hi.cast<double>();
      surfaces.push_back({{"object", p.object},
                          {"class", p.label},
                          {"shape", ShapeName(p.shape)},
                          {"min", Vec(a.cwiseMin(b))},
                          {"max", Vec(a.cwiseMax(b))}});
    }
    j["surfaces_note"] =
        "world-frame bounds; cylinders are vertical (along world_up) and ellipsoids inscribed in them";
    j["surfaces"] = std::move(surfaces);
  }
  return j.dump() + "\n";
}

std::string LandmarksCsv(const SyntheticCity& sim) {
  std::string text = "name,lat,lon,alt,category\n";
  for (const RouteLandmark& l : sim.Landmarks()) {
    std::string name = l.place->name;
    if (name.find_first_of(",\"") != std::string::npos) {
      std::string quoted = "\"";
      for (const char c : name) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
      name = quoted + "\"";
    }
    text += fmt::format("{},{:.9f},{:.9f},{:.3f},{}\n", name, l.wgs84.latitude_deg, l.wgs84.longitude_deg,
                        l.wgs84.altitude_m, l.place->category);
  }
  return text;
}

void WriteFrameImages(const RenderedFrame& images, size_t frame, const fs::path& sequence_dir,
                      int png_compression) {
  const std::string name = FrameName(frame);
  tbb::parallel_invoke([&] { WritePng(sequence_dir / "image_0" / name, images.left, png_compression); },
                       [&] { WritePng(sequence_dir / "image_1" / name, images.right, png_compression); },
                       [&] { WritePng(sequence_dir / "label_0" / name, images.labels, png_compression); },
                       [&] { WritePng(sequence_dir / "depth_0" / name, images.depth, png_compression); });
}

void WriteFrame(const SyntheticCity& sim, size_t frame, const fs::path& sequence_dir, int png_compression) {
  WriteFrameImages(sim.Render(frame, kRenderAll), frame, sequence_dir, png_compression);
}

namespace {

void CheckOutputFolder(const fs::path& out, bool overwrite) {
  std::error_code ec;
  if (!fs::is_directory(out, ec)) return;
  size_t entries = 0;
  std::string example;
  for (const auto& entry : fs::directory_iterator(out, ec)) {
    if (entries++ == 0) example = entry.path().filename().string();
  }
  if (entries == 0) return;
  if (!fs::exists(out / "scene.json", ec)) {
    throw InvalidArgument(fmt::format(
        "{}: the output folder is not empty and holds no synthetic dataset ({} entries, e.g. {}); choose a "
        "new or empty folder",
        out.string(), entries, example));
  }
  if (!overwrite) {
    throw InvalidArgument(fmt::format(
        "{}: the output folder holds an earlier synthetic dataset; pass --overwrite to replace it, or choose "
        "another folder",
        out.string()));
  }
}

}  // namespace

void WriteDataset(const SyntheticCity& sim, const fs::path& out, const DatasetOptions& options) {
  options.Check();
  Require(!out.empty(), "WriteDataset: empty output folder");
  CheckOutputFolder(out, options.overwrite);
  const fs::path seq_dir = out / "sequences" / options.sequence;
  {
    std::error_code ec;
    fs::remove(seq_dir / "times.txt", ec);  // the earlier dataset's, until this one is complete
  }
  for (const char* sub : {"image_0", "image_1", "label_0", "depth_0"}) {
    std::error_code ec;
    fs::create_directories(seq_dir / sub, ec);
    if (ec) throw InputError(out, "cannot create the output folder: " + ec.message());
  }
  // The small files first: a folder that cannot be written fails fast.
  try {
    WriteFileAtomically(out / "scene.json", SceneJson(sim));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(out, std::string("cannot write into the output folder: ") + e.what());
  }
  WriteFileAtomically(out / "landmarks.csv", LandmarksCsv(sim));
  WriteKittiCalibration(seq_dir / "calib.txt", MakeKittiCalibration(sim.rig()));
  WriteKittiPoses(out / "poses" / (options.sequence + ".txt"), sim.WorldFromCameraAll());
  WriteOxtsFolder(out / "oxts", SimulateOxts(sim));

  ProgressReporter progress("synth", sim.num_frames(), options.progress);
  std::atomic<size_t> done{0};
  std::mutex progress_mutex;
  tbb::parallel_for(size_t{0}, sim.num_frames(), [&](size_t f) {
    if (InterruptRequested()) return;
    WriteFrame(sim, f, seq_dir, options.png_compression);
    const size_t n = ++done;
    std::lock_guard<std::mutex> lock(progress_mutex);
    progress.Update(n);
  });
  if (InterruptRequested()) {
    throw Interrupted(
        InterruptSignal(),
        fmt::format("synth: interrupted by {} after {} of {} frames; {} is incomplete (it has no "
                    "times.txt): render it again with --overwrite",
                    InterruptName(), done.load(), sim.num_frames(), out.string()));
  }
  for (const char* sub : {"image_0", "image_1", "label_0", "depth_0"})
    RemoveStale(seq_dir / sub, sim.num_frames());
  std::vector<double> times(sim.num_frames());
  for (size_t f = 0; f < times.size(); ++f) times[f] = sim.Timestamp(f);
  WriteTimes(seq_dir / "times.txt", times);
  progress.Finish(fmt::format("{} frames, {:.0f} m", sim.num_frames(), sim.route().length));
}

}  // namespace semslam::sim
