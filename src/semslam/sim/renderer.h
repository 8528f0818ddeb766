#pragma once
// Renders the town through a pinhole camera by ray casting, one ray per pixel, in parallel over image rows
// (TBB). Grey levels from the procedural textures lit by a sun and ambient light, distance haze, a smooth sky
// gradient and slight sensor noise seeded by frame and pixel (the same frame renders to the same bytes on any
// number of threads). Labels are the Cityscapes trainIds of the surfaces hit, depth their camera z.

#include <cstdint>
#include <opencv2/core/mat.hpp>

#include "semslam/geometry/camera.h"
#include "semslam/geometry/rigid3.h"
#include "semslam/sim/city.h"
#include "semslam/sim/raycaster.h"

namespace semslam::sim {

struct RenderOptions {
  double sensor_noise = 1.5;     // standard deviation of the per-pixel noise, grey levels
  double max_distance = 400.0;   // rays end here (sky beyond)
  double haze_distance = 900.0;  // contrast halves about every 0.7 of this
  double ambient = 0.55;
  double sun_strength = 0.6;
  double sun_azimuth_deg = 150.0;  // direction towards the sun, counter-clockwise from east
  double sun_elevation_deg = 48.0;
  bool parallel = true;
  // Level cameras cast whole image columns at once (SceneIndex::CastColumn); false: one ray per pixel.
  bool column_casting = true;
  void Check() const;
};

// Depth images: uint16, metres * 256, 0 where no surface (sky), clamped at 65535.
inline constexpr double kDepthScale = 256.0;

class Renderer {
 public:
  // `city` and `index` must outlive the renderer.
  Renderer(const City& city, const SceneIndex& index, const PinholeCamera& camera,
           const RenderOptions& options = {});

  // Renders the view of a camera at `town_from_camera` (camera frame: x right, y down, z forward).
  // `grey` (CV_8UC1) is always written; `labels` (CV_8UC1) and `depth` (CV_16UC1) when not null.
  // `noise_key` seeds the sensor noise (use a different key per frame and camera).
  void Render(const Rigid3d& town_from_camera, std::uint32_t noise_key, cv::Mat* grey,
              cv::Mat* labels = nullptr, cv::Mat* depth = nullptr) const;

  const PinholeCamera& camera() const { return camera_; }

 private:
  struct Pixel {
    float grey;
    std::uint8_t label;
    float z;  // camera z, 0 for the sky
  };
  // Shades a pixel whose ray (unit direction `dir`, `t` along it) hit `primitive` (-1: ground, -2: nothing).
  Pixel Shade(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float t, float z, int primitive,
              const Eigen::Vector3f& normal, int axis) const;
  void Store(const Pixel& pixel, int u, int v, std::uint32_t noise_key, cv::Mat* grey, cv::Mat* labels,
             cv::Mat* depth) const;
  // One ray per pixel (any camera orientation).
  void RenderRows(int row_begin, int row_end, const Eigen::Matrix3f& rotation, const Eigen::Vector3f& origin,
                  std::uint32_t noise_key, cv::Mat* grey, cv::Mat* labels, cv::Mat* depth) const;
  // Whole columns at once (level cameras: the image y axis points straight down).
  void RenderColumns(int col_begin, int col_end, const Eigen::Matrix3f& rotation,
                     const Eigen::Vector3f& origin, std::uint32_t noise_key, cv::Mat* grey, cv::Mat* labels,
                     cv::Mat* depth) const;

  const City& city_;
  const SceneIndex& index_;
  PinholeCamera camera_;
  RenderOptions options_;
  Eigen::Vector3f sun_;
  std::vector<float> xn_, yn_;  // normalized image coordinates of columns and rows
};

}  // namespace semslam::sim
