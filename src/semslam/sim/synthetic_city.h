#pragma once
// The synthetic city as a library: town, route, cameras and ground truth from one options struct, without
// writing files. Frames are rendered on demand; poses, classes of surfaces, landmarks and GPS come from the
// same model, so tests can compare anything the SLAM system estimates against the truth.
//
// Frames: town = ENU of the WGS84 origin (x east, y north, z up); world = the first left camera's frame
// (x right, y down, z forward), as in KITTI. enu_from_world maps world points into ENU.

#include <cstdint>
#include <memory>
#include <opencv2/core/mat.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "semslam/geo/wgs84.h"
#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/sim/city.h"
#include "semslam/sim/raycaster.h"
#include "semslam/sim/renderer.h"
#include "semslam/sim/route.h"

namespace semslam::sim {

// KITTI's grey stereo camera (sequences 00-02): 1241x376, f = 718.856, principal point at the centre,
// baseline 0.54 m.
struct CameraOptions {
  int width = 1241;
  int height = 376;
  double focal = 718.856;
  double baseline = 0.54;
  void Check() const;
};

struct GpsOptions {
  Wgs84 origin{49.0, 8.4, 115.0};     // WGS84 of the town origin (ENU origin)
  double noise = 1.0;                 // Gaussian position noise, metres (each axis)
  int every = 1;                      // a fix every N frames
  double dropout = 0.0;               // probability that a fix is missing (never the first)
  double outliers = 0.0;              // probability that a fix is off by `outlier_distance`
  double outlier_distance = 50.0;     // metres, horizontal
  double start_epoch = 1600000000.0;  // Unix seconds of frame 0 (oxts timestamps = epoch + frame time)
  std::uint64_t seed = 0;             // 0: derived from the city seed
  void Check() const;
};

struct SynthOptions {
  std::string preset = "default";
  CityOptions city;
  RouteOptions route;
  CameraOptions camera;
  RenderOptions render;
  GpsOptions gps;
  void Check() const;
};

// Named option sets: "default" (8x8 blocks, parked cars, a few persons and bicycles), "small" (5x5 blocks),
// "dense" (more traffic, persons and trees), "static" (no parked cars, persons or bicycles).
// Throws InvalidArgument listing the names for an unknown one.
SynthOptions PresetOptions(std::string_view name);
std::vector<std::string> PresetNames();

// Which images Render() produces.
enum RenderParts : unsigned {
  kRenderLeft = 1u,
  kRenderRight = 2u,
  kRenderLabels = 4u,
  kRenderDepth = 8u,
  kRenderAll = 15u,
};

struct RenderedFrame {
  cv::Mat left;    // CV_8UC1
  cv::Mat right;   // CV_8UC1
  cv::Mat labels;  // CV_8UC1, trainIds of the left image
  cv::Mat depth;   // CV_16UC1, left camera z * 256, 0 = sky
};

// A named place along the route (landmarks.csv).
struct RouteLandmark {
  const Place* place = nullptr;
  Eigen::Vector3d world = Eigen::Vector3d::Zero();  // position in the world frame
  Wgs84 wgs84;
  int nearest_frame = 0;
  double distance = 0;  // from the nearest camera centre, metres (horizontal)
};

struct SurfaceClass {
  int label = 0;        // trainId
  double distance = 0;  // metres from the point to the surface
  int object = -1;      // City::objects index, -1 for the road surface
};

// A frame that comes back to an earlier place: close by and looking the same way.
struct Revisit {
  int frame = 0;
  int earlier_frame = 0;
  double distance = 0;   // metres between the camera centres
  double angle_deg = 0;  // between the viewing directions
};

class SyntheticCity {
 public:
  // Generates the town and the route. Throws InvalidArgument on bad options.
  explicit SyntheticCity(const SynthOptions& options);
  ~SyntheticCity();
  SyntheticCity(const SyntheticCity&) = delete;
  SyntheticCity& operator=(const SyntheticCity&) = delete;

  const SynthOptions& options() const { return options_; }
  const City& city() const { return city_; }
  const Route& route() const { return route_; }
  size_t num_frames() const { return route_.town_from_camera.size(); }
  const StereoRig& rig() const { return rig_; }
  double Timestamp(size_t frame) const { return static_cast<double>(frame) / options_.route.rate_hz; }

  // Left camera pose of a frame; world = the first left camera's frame.
  Rigid3d WorldFromCamera(size_t frame) const;
  std::vector<Rigid3d> WorldFromCameraAll() const;
  const Rigid3d& EnuFromWorld() const { return enu_from_world_; }  // = town_from_world
  Rigid3d WorldFromTown() const { return enu_from_world_.Inverse(); }
  const EnuFrame& enu() const { return *enu_; }
  Wgs84 ToWgs84(const Eigen::Vector3d& world_point) const;

  // Renders the frame's images (thread-safe; parallel inside unless options.render.parallel is false).
  RenderedFrame Render(size_t frame, unsigned parts = kRenderAll) const;

  // The class of the surface nearest to a world point (the road plane, or the nearest primitive within 3 m).
  SurfaceClass ClassAt(const Eigen::Vector3d& world_point) const;

  // 8-20 named buildings and places along the driven route (fewer only if the town has fewer), in order of
  // their nearest frame.
  std::vector<RouteLandmark> Landmarks() const;

  // The first frame of every run of frames that revisit an earlier place (camera centres within
  // `max_distance`, directions within `max_angle_deg`, at least `min_gap` frames apart), with the closest
  // earlier frame.
  std::vector<Revisit> Revisits(double max_distance = 3.0, double max_angle_deg = 10.0,
                                int min_gap = 100) const;

  const SceneIndex& index() const { return *index_; }

 private:
  SynthOptions options_;
  City city_;
  Route route_;
  StereoRig rig_;
  Rigid3d enu_from_world_;
  std::unique_ptr<EnuFrame> enu_;
  std::unique_ptr<SceneIndex> index_;
  std::unique_ptr<Renderer> renderer_;
};

}  // namespace semslam::sim
